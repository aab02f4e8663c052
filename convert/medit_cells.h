// The volume elements of a Medit mesh, shared by the ASCII (.mesh) and binary (.meshb) readers: which
// keywords hold them, and how hexahedra, prisms and pyramids become tetrahedra.
//
// Corner numbering. Medit (and libMeshb, which writes the same keywords in binary) numbers a
// hexahedron's corners 1-4 round one quadrilateral face and 5-8 round the opposite face, corner 4+i
// joined to corner i by an edge; a prism's corners 1-3 and 4-6 are its two triangles, 3+i joined to i;
// a pyramid's corners 1-4 go round its base and 5 is its apex. That is VTK's order for
// VTK_HEXAHEDRON, VTK_WEDGE and VTK_PYRAMID once made 0-based (Gmsh's Medit reader builds its
// hexahedra from the eight indices as they stand, and meshio maps Medit's Hexahedra to VTK's
// hexahedron without a permutation), so Medit corner k is VTK corner k - 1 for all three. Which way a
// face turns does not matter: the tetrahedra are oriented afterwards.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "convert/cell_split.h"
#include "convert/import.h"

namespace gtn {

// A Medit keyword that holds volume elements: its name, the vertex numbers per element (a reference
// number follows them), how many of them are the corners the element keeps (the first ones: a
// TetrahedraP2 element lists its 4 corners, then its 6 mid-edge nodes, which stay as unreferenced
// points; HexahedraQ2, PrismsP2 and PyramidsP2 elements list the corners of Hexahedra, Prisms and
// Pyramids in their order, then their other nodes) and the VTK cell type with the same corner order.
struct MeditVolumeKeyword {
  const char* name;
  const char* singular;
  int corners;
  int vtk_type;
  int nodes;
};
// Tetrahedra, Hexahedra, Prisms, Pyramids, TetrahedraP2, HexahedraQ2, PrismsP2, PyramidsP2.
inline constexpr size_t kMeditVolumeKinds = 8;
extern const MeditVolumeKeyword kMeditVolumeKeywords[kMeditVolumeKinds];
inline constexpr int kMeditMaxNodes = 27;  // the most nodes of an element (HexahedraQ2)
// The second-order form of a linear keyword (Tetrahedra: TetrahedraP2, Hexahedra: HexahedraQ2, ...),
// or null for a second-order one.
const MeditVolumeKeyword* secondOrderForm(const MeditVolumeKeyword& linear);

// The volume elements read so far. Tetrahedra go straight to mesh.tets (their references to
// tet_refs); the other elements wait in `others`, 0-based, until finishMeditImport splits them.
//
// A keyword may have several sections (meshio writes one per block of cells); they are read one
// after the other. libMeshb keeps only the last one it meets, so a warning says which were joined.
// Keywords may come in any order (GMF), elements before Vertices too: the vertex numbers of those
// are checked once the vertices are known (checkLateVertices).
struct MeditCells {
  std::vector<int32_t> tet_refs;
  VtkCells others;
  std::vector<int32_t> other_refs;
  std::string sections[kMeditVolumeKinds];  // per keyword of kMeditVolumeKeywords, where its sections begin ("line 7")
  int section_count[kMeditVolumeKinds] = {};
  // Per keyword of kMeditVolumeKeywords: its elements with more nodes than corners (TetrahedraP2,
  // HexahedraQ2, ...), kept by their corners.
  uint64_t reduced[kMeditVolumeKinds] = {};
  // The largest vertex number read before the Vertices section, and where: the element ("tetrahedron
  // 5") and a place (a line, or a byte offset) for the error.
  int64_t late_vertex = 0;
  std::string late_element;
  uint64_t late_place = 0;
  bool empty() const { return tet_refs.empty() && other_refs.empty(); }
  // Notes a section of `kw` that begins at `where` ("line 7", "byte offset 120").
  void addSection(const MeditVolumeKeyword& kw, const std::string& where);
  // Warnings for the keywords that had several sections.
  void warnAboutSections(ImportResult* result) const;
  // Notes vertex number v (1 or more) of `element` at `place`, read before the vertices.
  void noteLateVertex(int64_t v, const std::string& element, uint64_t place) {
    if (v > late_vertex) late_vertex = v, late_element = element, late_place = place;
  }
  // Makes room for n elements of `kw`.
  void reserve(const MeditVolumeKeyword& kw, size_t n, TetMesh* mesh);
  // One element of `kw`: its corners (0-based; the first kw.corners of its nodes) and its reference.
  void add(const MeditVolumeKeyword& kw, const uint32_t* corners, int32_t ref, TetMesh* mesh);
};

// Why a Medit mesh without volume elements is refused; `skipped` lists the higher-order sections
// that were skipped (empty if none).
std::string noVolumeElements(const std::string& skipped);

// Ends a Medit import once result->mesh has its points, point fields and tetrahedra: splits the
// other elements into tetrahedra (options.split, the VTK importers' warnings), adds the cell field
// "ref" (each tetrahedron carries the reference of its element: tetrahedra first, then the other
// elements in file order), normalises orientation, checks the mesh and reads the solution files of
// options.medit_solutions (readMeditSolutions: before the split when there are other elements, so
// that vertex values count the file's vertices and are averaged onto any point the split adds;
// after it for tetrahedra alone, whose element values are kept). `format` names the source
// ("medit", "meshb") in the metadata.
Status finishMeditImport(const std::string& path, const char* format, MeditCells* cells, const ImportOptions& options,
                         ImportResult* result);

// Reads Medit solution files (.sol ASCII or .solb binary, told apart by their first bytes) into
// result->mesh (called by finishMeditImport): SolAtVertices sections become point fields and, when the
// mesh was tetrahedra only (`tets_only`), SolAtTetrahedra sections cell fields, named after the file
// (u.sol: "u", or "u_1", "u_2" ... for several types), float32 in version 1 files, float64 after.
// Counts must match the mesh's; other solution sections are skipped with a warning.
Status readMeditSolutions(const std::vector<std::string>& paths, bool tets_only, ImportResult* result);

}  // namespace gtn
