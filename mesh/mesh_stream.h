// The mesh stream (docs/design.md): the one event sequence the decoder produces and the simplifier,
// the renderer and the in-memory builder consume, so that each piece of data passes through memory
// once. Order of events for one level:
//   beginLevel, then vertex/boundaryTriangle events for the boundary surface (each triangle after its
//   three vertices), endBoundary, then vertex and tet events in peeling order (a tetrahedron after
//   its four vertices), retireVertex once a vertex's last tetrahedron has been emitted, endLevel.
// Vertex ids are assigned in emission order within the level: the k-th vertex event has id k.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <typeinfo>
#include <vector>

#include "mesh/fresh_memory.h"
#include "mesh/tet_mesh.h"

namespace gtn {

struct FieldDesc {
  std::string name;
  uint32_t components = 1;
  ScalarType type = ScalarType::kFloat32;
  size_t itemBytes() const { return components * scalarSize(type); }
};

struct LevelHeader {
  uint32_t level = 0;   // 0 = the lossless mesh, i = stored mip level i
  uint64_t merges = 0;  // merges of the merge tree already applied to this level
  uint64_t points = 0;  // vertex events that will follow
  uint64_t tets = 0;    // tet events that will follow
  uint64_t boundary_triangles = 0;
  ScalarType coord_type = ScalarType::kFloat64;
  std::vector<FieldDesc> point_fields;  // values of a vertex event: these fields' items, concatenated
  std::vector<FieldDesc> cell_fields;   // values of a tet event: these fields' items, concatenated
  double bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};
  std::vector<std::pair<std::string, std::string>> metadata;
};

class MeshSink {
 public:
  virtual ~MeshSink() = default;
  virtual Status beginLevel(const LevelHeader& header) = 0;
  // `values` points at the concatenated items of header.point_fields (raw bytes in source type).
  virtual Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) = 0;
  // Outward-oriented boundary triangle of vertices already emitted.
  virtual Status boundaryTriangle(const uint32_t v[3]) = 0;
  virtual Status endBoundary() = 0;
  // A positively oriented tetrahedron of vertices already emitted; `cell_values` as for vertex().
  virtual Status tet(const uint32_t v[4], const uint8_t* cell_values) = 0;
  // No later event refers to vertex `id`.
  virtual Status retireVertex(uint32_t id) = 0;
  virtual Status endLevel() = 0;

  // A sink that assembles the whole mesh anyway may take a level that a decoder holds whole (a
  // structured piece) in one call instead of its events: takesWholeLevel() true, and then
  // wholeLevel() in place of beginLevel .. endLevel. `mesh` holds the level's points, tetrahedra and
  // fields as the events would have built them (vertex k is point k, tetrahedra in event order,
  // header's fields), `boundary` its boundary triangles in event order.
  virtual bool takesWholeLevel() const { return false; }
  virtual Status wholeLevel(const LevelHeader& header, TetMesh&& mesh, std::vector<std::array<uint32_t, 3>>&& boundary);
};

// A sink that only counts what arrives: for decoding to check a stream, and for timing a decoder.
class CountingSink : public MeshSink {
 public:
  Status beginLevel(const LevelHeader&) override { return Status::ok(); }
  Status vertex(uint32_t, const double*, const uint8_t*) override {
    ++vertices;
    return Status::ok();
  }
  Status boundaryTriangle(const uint32_t*) override {
    ++boundary_triangles;
    return Status::ok();
  }
  Status endBoundary() override { return Status::ok(); }
  Status tet(const uint32_t*, const uint8_t*) override {
    ++tets;
    return Status::ok();
  }
  Status retireVertex(uint32_t) override { return Status::ok(); }
  Status endLevel() override { return Status::ok(); }

  uint64_t vertices = 0, boundary_triangles = 0, tets = 0;
};

// A sink that assembles the stream into a TetMesh (the generic, whole-mesh consumer).
class TetMeshBuilder : public MeshSink {
 public:
  Status beginLevel(const LevelHeader& header) override;
  Status vertex(uint32_t id, const double xyz[3], const uint8_t* values) override;
  Status boundaryTriangle(const uint32_t v[3]) override;
  Status endBoundary() override { return Status::ok(); }
  Status tet(const uint32_t v[4], const uint8_t* cell_values) override;
  Status retireVertex(uint32_t) override { return Status::ok(); }
  Status endLevel() override { return Status::ok(); }
  // A subclass (which may watch the events) gets the events.
  bool takesWholeLevel() const override { return typeid(*this) == typeid(TetMeshBuilder); }
  Status wholeLevel(const LevelHeader& header, TetMesh&& mesh,
                    std::vector<std::array<uint32_t, 3>>&& boundary) override;

  const LevelHeader& header() const { return header_; }
  TetMesh& mesh() { return mesh_; }
  const std::vector<std::array<uint32_t, 3>>& boundary() const { return boundary_; }

 private:
  LevelHeader header_;
  TetMesh mesh_;
  std::vector<std::array<uint32_t, 3>> boundary_;
  // The pages of the storage reserved from the header's counts, mapped a step ahead of the appends.
  PopulatedPrefix coords_ready_, tets_ready_;
  std::vector<PopulatedPrefix> point_ready_, cell_ready_;
};

// Streams a whole level (as TetMeshBuilder assembled it: `mesh` with header's fields, `boundary`) to
// `sink` as events: every vertex in id order, the boundary triangles, the tetrahedra, then every
// vertex retired.
Status replayLevel(const LevelHeader& header, const TetMesh& mesh, const std::vector<std::array<uint32_t, 3>>& boundary,
                   MeshSink& sink);

}  // namespace gtn
