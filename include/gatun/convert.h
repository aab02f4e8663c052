// <gatun/convert.h>: importing mesh files into a Mesh, converting them to .gtn and other formats.
// Part of the Gatun API; <gatun/gatun.h> includes every part and says how errors, ownership and
// threads work for all of them.
#pragma once

#include <string>
#include <vector>

#include "gatun/mesh.h"
#include "gatun/result.h"
#include "gatun/write.h"

namespace gatun {

/*-************************************
 *  Converting
 **************************************/

/*! ImportOptions : how mesh files are read (the import options of `gtn convert`).
 *  `split`: hexahedra into 5 (alternating) or 6 (consistent diagonals) tetrahedra.
 *  `weld`: merge bit-identical points (seams between PLOT3D blocks or VTK pieces) and drop the
 *     tetrahedra that collapse.
 *  `exodus_time_step`: Exodus II, the 1-based time step whose variables become fields; 0 = the last. */
struct ImportOptions {
  int split = 6;
  bool weld = false;
  int exodus_time_step = 0;
};

/*! importMesh() : reads the mesh that `inputs` describe together, as `gtn convert` does: one mesh
 *  file, PLOT3D grid [Q] [function] files or a .p3d file, a TetGen basename or any of its files, a
 *  Medit mesh and its .sol/.solb files, VTK legacy or XML, OFF, gmsh, Exodus II, or a .gtn file (its
 *  level 0). Cells are split into tetrahedra and turned to positive orientation.
 *  `warnings` (optional) receives what the import changed or left out, each naming its file.
 *  Errors: kUsage (no input, bad options), kIo, kInvalidData / kUnsupported / kNotOurFile (a file
 *  that cannot be read as its format, naming the file and the place). */
Result<Mesh> importMesh(const std::vector<std::string>& inputs, const ImportOptions& options = {},
                        std::vector<std::string>* warnings = nullptr);

/*! ConvertOptions : importing, writing .gtn (`write`) and, for .vtu, zlib compression. */
struct ConvertOptions {
  ImportOptions import{};
  WriteOptions write{};
  bool compress = false;
};

/*! convert() : `gtn convert INPUTS... -o OUTPUT`: importMesh(inputs), then writes `output` by its
 *  extension: .gtn (as write() does), .vtu (VTK XML), .vtk (legacy VTK), or .node / .ele (TetGen).
 *  `warnings` (optional) receives the import's and the writer's warnings.
 *  Errors: those of importMesh() and write(); kUsage for an unknown output extension or an output
 *  that is one of the inputs. */
Error convert(const std::vector<std::string>& inputs, const std::string& output, const ConvertOptions& options = {},
              std::vector<std::string>* warnings = nullptr);

}  // namespace gatun
