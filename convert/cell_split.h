// VTK cells into tetrahedra, conformingly: the legacy and XML VTK importers both hand their cells here.
//
// Rule: every quadrilateral face is cut along the diagonal through its vertex with the smallest global
// index, and every pentagon or hexagon as the fan from that vertex. Two cells sharing a face see the
// same indices, so they cut it the same way. Each hexahedron, wedge, pyramid or pentagonal or
// hexagonal prism is then split as the cone from its own smallest-index vertex v over the faces that
// do not contain v (each already triangulated by the rule): every face that does contain v has v as
// its smallest vertex, so its diagonals pass through v, which is exactly how the cone cuts it. Hence
// the cut always agrees with the face rule and no configuration of Dompierre et al. (1999) that needs
// a Steiner point can arise: hexahedra give 6 tetrahedra, wedges 3, pyramids 2, pentagonal prisms 9
// (at most), hexagonal prisms 12. Polyhedra
// (VTK_POLYHEDRON) are split the same way from their face streams: a tetrahedron for each triangle
// of each face that does not contain the cell's smallest vertex. (The cone is a valid split of a
// convex cell, as VTK's prisms are meant to be, and of a polyhedron star-shaped from that vertex.)
// A cell that is not convex can make the cone mix inverted and positive tetrahedra; it is then coned
// from another vertex the face rule allows, and when every such cone mixes (a warped face, say), from a
// Steiner point added inside it (the mean of its corners, or of its kernel's vertices), over all its
// faces: with GridHexSplitter's warped grid cells, the only cases that add points
// (ImportReport::steiner_points).
// With split == 5 a hexahedron whose six face diagonals form one of the two inscribed tetrahedra
// ({0,2,5,7} or {1,3,4,6}) is cut into 5 instead.
// Voxels are hexahedra numbered x fastest; quadratic tetrahedra, hexahedra, wedges and pyramids keep
// only their corners (listed first). Cells of lower dimension (vertices, lines, triangles, quads,
// polygons, linear or not), which volume-mesh files carry as boundary faces and feature edges, are
// skipped with a warning.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "convert/import.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// Cells as VTK lays them out: cell c has types[c] and the point indices
// connectivity[offsets[c] .. offsets[c + 1]); offsets has one entry more than types, starting at 0.
// Polyhedra (VTK_POLYHEDRON, 42) also have a face stream: for each polyhedron its number of faces,
// then per face its number of points and the points. XML files keep the streams apart (faces, and
// faceoffsets: per cell the end of its stream in faces, -1 for other cells); when face_offsets is
// empty, a polyhedron's connectivity is its face stream (the legacy layout).
struct VtkCells {
  std::vector<int32_t> types;
  std::vector<int64_t> offsets{0};
  std::vector<int64_t> connectivity;
  std::vector<int64_t> faces;
  std::vector<int64_t> face_offsets;
  // Faces listed once for the two cells they bound (Exodus NFACED): each winds outward for one of
  // them only, so a polyhedron whose faces the split turns to wind alike is not reported.
  bool faces_shared = false;
};

// Points added inside cells (splitVtkCells, GridHexSplitter): point k has coordinates
// coords[3k .. 3k + 3) and lies in the cell of the input points corners[corner_offsets[k] ..
// corner_offsets[k + 1]), whose mean gives its point fields.
struct SteinerPoints {
  std::vector<double> coords;
  std::vector<size_t> corner_offsets{0};
  std::vector<uint32_t> corners;
};

// Splits every cell into tetrahedra: appends them to *tets and, for each, its source cell to
// *tet_cell. Tetrahedra that a degenerate cell (a repeated point index) makes flat by repetition are
// dropped and counted in report->collapsed_tets. Cells of lower dimension are skipped (a warning
// counts them by type). Fails, naming `path`, when a volume cell type is not supported or no cell is
// a volume cell (with each type's number, name and how many cells have it), when a cell has the
// wrong number of points, or when an index is out of range.
// `coords` (3 per point, or nullptr): with them, a cell whose cone from its smallest vertex would mix
// inverted and positive tetrahedra (a cell that is not convex) is coned from another vertex that the
// face rule allows, when one gives no such mix, and otherwise, with `steiner`, from a point added to
// *steiner (numbered from num_points on; float32: its coordinates rounded to float32), when that
// gives no such mix.
Status splitVtkCells(const std::string& path, const VtkCells& cells, size_t num_points, const double* coords, int split,
                     std::vector<Tet>* tets, std::vector<uint32_t>* tet_cell, ImportReport* report,
                     SteinerPoints* steiner = nullptr, bool float32 = false);

// Splits the hexahedra of a structured grid (PLOT3D, VTK's structured datasets) into tetrahedra as
// splitHexFive (odd: the cell's parity) and splitHexSix do, appending them to mesh->tets (and each
// one's `cell` to *tet_cell, when given), except a cell whose pieces would mix inverted and positive
// tetrahedra (a warped cell): that one is split around a Steiner point over its faces, cut along the
// same diagonals, so that its neighbours still agree. finish() appends the added points to the mesh
// (point fields: floating-point ones the mean of the cell's corners, integer ones its smallest
// corner's) and reports them; the mesh's points must not change before it.
class GridHexSplitter {
 public:
  explicit GridHexSplitter(TetMesh* mesh, std::vector<uint32_t>* tet_cell = nullptr);
  ~GridHexSplitter();
  void split(const uint32_t h[8], int split, bool odd, uint32_t cell = 0);
  void finish(ImportReport* report);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The points of a rectilinear grid, i fastest: (x[i], y[j], z[k]) from axes[0..2].
void rectilinearPoints(const std::vector<double> axes[3], std::vector<double>* coords);
// The points of VTK image data, i fastest: origin + direction (first + index) * spacing per axis, in
// double (direction: 9 numbers row by row, or nullptr for the identity, which adds no rounding).
void imagePoints(const uint64_t dims[3], const int64_t first[3], const double origin[3], const double spacing[3],
                 const double* direction, std::vector<double>* coords);

// The common end of the structured datasets of both VTK importers (legacy STRUCTURED_GRID,
// RECTILINEAR_GRID, STRUCTURED_POINTS; XML .vts, .vtr, .vti): result->mesh holds the dims[0] x
// dims[1] x dims[2] points (i fastest) and their point fields. Splits the hexahedral cells (i fastest,
// the order of `cell_fields`) like PLOT3D's: 5 tetrahedra with alternating parity or 6 around one
// diagonal (options.split), spreads the cell fields over the tetrahedra and normalises orientation.
Status finishStructuredImport(const std::string& path, const uint64_t dims[3], const std::vector<Field>& cell_fields,
                              const ImportOptions& options, ImportResult* result);

// The common end of both VTK importers: splits `cells` into result->mesh.tets (points and point
// fields already set), drops the cells that a vtkGhostType cell array marks hidden (and, with
// `duplicate_tets`, those it marks as another piece's, counting their tetrahedra there), spreads
// the per-cell fields over the tetrahedra into mesh.cell_fields, and normalises orientation
// (finishImport). With options.weld the cells are split seeing each point as its welded identity
// (weldIdentities), so that the face rule cuts a face that pieces share alike in each piece.
Status finishVtkImport(const std::string& path, const VtkCells& cells, const std::vector<Field>& cell_fields,
                       const ImportOptions& options, ImportResult* result, size_t* duplicate_tets = nullptr);

}  // namespace gtn
