// libFuzzer target below the container's checksums: arbitrary bytes straight into the level decoder
// and the merge-tree decoder, which a checksummed file only reaches with valid chunks. Layout of an
// input: byte 0 selects the decoder; for a level, bytes 1..8 give small counts and the field layout,
// then three length bytes split the rest into the boundary, connectivity and geometry streams, the
// remainder being the point-field stream.
#include <cstddef>
#include <cstdint>
#include <span>

#include "codec/level_codec.h"
#include "codec/merge_tree_coder.h"
#include "mesh/mesh_stream.h"

namespace {

class NullSink : public gtn::MeshSink {
 public:
  gtn::Status beginLevel(const gtn::LevelHeader&) override { return gtn::Status::ok(); }
  gtn::Status vertex(uint32_t, const double*, const uint8_t*) override { return gtn::Status::ok(); }
  gtn::Status boundaryTriangle(const uint32_t*) override { return gtn::Status::ok(); }
  gtn::Status endBoundary() override { return gtn::Status::ok(); }
  gtn::Status tet(const uint32_t*, const uint8_t*) override { return gtn::Status::ok(); }
  gtn::Status retireVertex(uint32_t) override { return gtn::Status::ok(); }
  gtn::Status endLevel() override { return gtn::Status::ok(); }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 12) return 0;
  if (data[0] & 1) {
    auto tree = gtn::decodeMergeTree(std::span<const uint8_t>(data + 2, size - 2), data[1] % 64, "fuzz");
    (void)tree.isOk();
    return 0;
  }
  gtn::LevelHeader h;
  h.points = data[1] % 64;
  h.tets = data[2] % 128;
  h.boundary_triangles = data[3] % 128;
  h.coord_type = (data[4] & 1) ? gtn::ScalarType::kFloat32 : gtn::ScalarType::kFloat64;
  if (data[4] & 2) h.point_fields.push_back({"f", 1u + (data[4] >> 6), static_cast<gtn::ScalarType>(data[5] % 10)});
  if (data[4] & 4) h.cell_fields.push_back({"c", 1, static_cast<gtn::ScalarType>(data[6] % 10)});
  size_t pos = 9;
  const size_t lens[3] = {data[7], data[8], static_cast<size_t>(data[7] ^ data[8])};
  std::span<const uint8_t> streams[3];
  for (int i = 0; i < 3; ++i) {
    const size_t n = std::min(lens[i], size - pos);
    streams[i] = std::span<const uint8_t>(data + pos, n);
    pos += n;
  }
  gtn::LevelPayload payload;
  payload.boundary = streams[0];
  payload.connectivity = streams[1];
  payload.geometry = streams[2];
  const std::span<const uint8_t> rest(data + pos, size - pos);
  if (!h.point_fields.empty()) payload.point_fields.push_back(rest);
  if (!h.cell_fields.empty()) payload.cell_fields.push_back(rest);
  NullSink sink;
  gtn::DecodeStats stats;
  (void)gtn::decodeLevel(h, payload, sink, &stats, "fuzz").isOk();
  return 0;
}
