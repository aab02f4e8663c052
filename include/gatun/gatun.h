/*
 * gatun.h: the public C++ API of Gatun, compressed tetrahedral meshes (.gtn files).
 *
 * Include <gatun/gatun.h>, or the part you need, and link the CMake target gatun::gatun
 * (find_package(gatun)). Everything is in namespace gatun; nothing else of the library is public.
 *   <gatun/result.h>    version(), Error, Result<T>
 *   <gatun/mesh.h>      Mesh, Field, ScalarType
 *   <gatun/read.h>      Reader, readInfo(), read()
 *   <gatun/write.h>     write()
 *   <gatun/convert.h>   importMesh(), convert()
 *   <gatun/validate.h>  validate()
 *   <gatun/render.h>    render(), writePng()
 *
 * What it does, part by part:
 *   - reading:    open a .gtn file, describe it (FileInfo), decode a stored level or any
 *                 simplification ratio into a Mesh (points, tetrahedra, point and cell fields), all
 *                 fields or only some (Reader, readInfo, read);
 *   - writing:    a Mesh to a .gtn file with its mip levels and merge trees, as `gtn convert` writes
 *                 it (write);
 *   - converting: any input the importers read (PLOT3D, TetGen, VTK legacy and XML, Medit, OFF, gmsh,
 *                 Exodus II, .gtn) into a Mesh, or into a .gtn, .vtu, .vtk or TetGen file as
 *                 `gtn convert` does (importMesh, convert);
 *   - validating: a .gtn file or mesh files to the report of `gtn validate` (validate);
 *   - rendering:  a .gtn file or mesh files to an RGB image as `gtn render` draws it, and PNG output
 *                 (render, writePng).
 *
 * Errors: no function throws for bad input or a failed operation. A function that returns nothing
 * returns an Error, one that returns a value a Result<T>; on failure either carries an ErrorCode and
 * the message the `gtn` command prints, which names the file, the place in it and the reason. The
 * only exceptions are std::bad_alloc when memory runs out and std::bad_optional_access from
 * Result<T>::value() on a failed result.
 *
 * Ownership: every type here is a plain value type (or, for Reader, a move-only handle) that owns its
 * data; nothing returned refers to library-internal memory, and nothing the caller passes is kept
 * after a call returns.
 *
 * Thread safety: every function may be called from several threads at once, provided that no two
 * calls write the same file and no Reader is used by two threads at once (distinct Readers are
 * independent, even on the same file). The one exception is importing Exodus II files, which goes
 * through the Exodus and netCDF libraries: do not import two of them at once. Several functions use
 * worker threads of their own (oneTBB).
 *
 * Files are written atomically: a temporary file is renamed over the target only when everything
 * succeeded; inputs are never modified.
 */
#pragma once

#include "gatun/convert.h"
#include "gatun/mesh.h"
#include "gatun/read.h"
#include "gatun/render.h"
#include "gatun/result.h"
#include "gatun/validate.h"
#include "gatun/write.h"
