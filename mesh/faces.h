// Face adjacency and the boundary surface of a tetrahedral mesh. Faces are identified by their three
// vertex indices (not positions): unwelded coincident points give distinct faces, as in the paper's
// Table 1 counts.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "mesh/index.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// Local faces of a tetrahedron: face k is opposite vertex k, listed so that for a positively oriented
// tetrahedron its normal (right-hand rule) points outward.
extern const int kTetFace[4][3];
// Local edges of a tetrahedron: those of face 3's corners (0, 1, 2) first, then the three to corner 3
// (the order in which the level codec codes edge points, spec section 10.5).
extern const int kTetEdge[6][2];

inline constexpr uint32_t kNoNeighbor = kNoIndex;  // boundary face
constexpr uint32_t kNonManifold = 0xFFFFFFFEu;     // face shared by three or more tetrahedra

struct FaceAdjacency {
  // neighbor[4 * t + k]: the tetrahedron across face k of tetrahedron t, kNoNeighbor on the boundary,
  // kNonManifold where three or more tetrahedra share the face.
  std::vector<uint32_t> neighbor;
  uint64_t faces = 0;               // distinct triangles
  uint64_t boundary_faces = 0;      // triangles in exactly one tetrahedron
  uint64_t non_manifold_faces = 0;  // triangles in three or more tetrahedra
};

// The face slots (4 bytes each) are grouped in passes over the tetrahedra of at most `pass_slots` slots
// each (a vertex's group is never split); 0, the default: one pass up to 2^24 slots, two beyond (a
// large mesh's check held half as many).
FaceAdjacency computeFaceAdjacency(const TetMesh& mesh, uint64_t pass_slots = 0);

// What a check needs of the face adjacency, in 2 bytes a tetrahedron instead of 16: per tetrahedron,
// which of its faces are in no other tetrahedron (bit kBoundary << k for face k), which are in three
// or more (kNonManifold << k), and whether a tetrahedron shares a face with one that `flat` marks
// (kNextToFlat; never without `flat`); with `alike`, whether a tetrahedron has a face that the
// other tetrahedron on it lists in the same direction (kAlike: facesOpposite is false; never
// without `alike`); and the counts of FaceAdjacency. `pass_slots` as above.
struct FaceClasses {
  static constexpr uint16_t kBoundary = 1, kNonManifold = 16, kNextToFlat = 256, kAlike = 512;
  std::vector<uint16_t> mask;
  uint64_t faces = 0;
  uint64_t boundary_faces = 0;
  uint64_t non_manifold_faces = 0;
};
FaceClasses classifyFaces(const TetMesh& mesh, const std::vector<uint8_t>* flat = nullptr, uint64_t pass_slots = 0,
                          bool alike = false);

// Whether face k of tetrahedron a and the same triangle as a face of tetrahedron b run in opposite
// directions (a's outward listing against b's), as they do in a consistently oriented mesh; b must
// hold the face's three vertices.
bool facesOpposite(const Tet& a, int k, const Tet& b);

using Triangle = std::array<uint32_t, 3>;

// Boundary triangles, outward oriented when the tetrahedra are positively oriented, in tetrahedron
// order (tetrahedron index, then local face).
std::vector<Triangle> boundaryTriangles(const TetMesh& mesh, const FaceAdjacency& adjacency);
// The same from the faces' classes.
std::vector<Triangle> boundaryTriangles(const TetMesh& mesh, const FaceClasses& classes);

}  // namespace gtn
