// How the decoder fuzz target reads its input, shared by the target (fuzz_gtn_decoder.cpp) and the
// replay of its corpus as an ordinary test (tests/validate/fuzz_corpus_test.cpp). Layout of an input:
// byte 0 selects the decoder (odd: merge tree, with byte 1 the point count); for a level, bytes 1..6
// give small counts and the field layout (byte 4's bits 3 and 4 leave the point or the cell field out of
// the decode, as a renderer does), bytes 7 and 8 the lengths of the boundary and connectivity streams
// (their xor that of the geometry stream), the remainder being the field streams.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>

#include "codec/level_codec.h"
#include "codec/merge_tree_coder.h"
#include "mesh/mesh_stream.h"

namespace gtn::fuzz {

// Runs one input through the level decoder or the merge-tree decoder; any outcome but a crash, a
// sanitizer report or a hang is fine. Returns whether the decoder accepted the input.
inline bool decodeFuzzInput(const uint8_t* data, size_t size) {
  if (size < 12) return false;
  if (data[0] & 1) {
    // A version 3 tree decodes against a level: a strip of tetrahedra over the points.
    const uint32_t points = data[1] % 64;
    TetMesh strip;
    for (uint32_t v = 0; v < points; ++v)
      strip.coords.insert(strip.coords.end(), {double(v), double(v % 3), double(v % 5)});
    for (uint32_t v = 0; v + 3 < points; ++v) strip.tets.push_back({v, v + 1, v + 2, v + 3});
    return decodeMergeTree(std::span<const uint8_t>(data + 2, size - 2), points, "fuzz", &strip).isOk();
  }
  LevelHeader h;
  h.points = data[1] % 64;
  h.tets = data[2] % 128;
  h.boundary_triangles = data[3] % 128;
  h.coord_type = (data[4] & 1) ? ScalarType::kFloat32 : ScalarType::kFloat64;
  if (data[4] & 2) h.point_fields.push_back({"f", 1u + (data[4] >> 6), static_cast<ScalarType>(data[5] % 10)});
  if (data[4] & 4) h.cell_fields.push_back({"c", 1, static_cast<ScalarType>(data[6] % 10)});
  size_t pos = 9;
  const size_t lens[3] = {data[7], data[8], static_cast<size_t>(data[7] ^ data[8])};
  std::span<const uint8_t> streams[3];
  for (int i = 0; i < 3; ++i) {
    const size_t n = std::min(lens[i], size - pos);
    streams[i] = std::span<const uint8_t>(data + pos, n);
    pos += n;
  }
  LevelPayload payload;
  payload.boundary = streams[0];
  payload.connectivity = streams[1];
  payload.geometry = streams[2];
  const std::span<const uint8_t> rest(data + pos, size - pos);
  if (!h.point_fields.empty()) payload.point_fields.push_back(rest);
  if (!h.cell_fields.empty()) payload.cell_fields.push_back(rest);
  DecodeFields fields;
  fields.point.assign(h.point_fields.size(), (data[4] & 8) == 0);
  fields.cell.assign(h.cell_fields.size(), (data[4] & 16) == 0);
  CountingSink sink;
  DecodeStats stats;
  return decodeLevel(h, payload, sink, &stats, "fuzz", &fields).isOk();
}

}  // namespace gtn::fuzz
