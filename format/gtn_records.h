// Payloads of the container's own chunks (spec/gtn-format.md): the file header (GHDR), the level
// header (LHDR), the directory (DIRC) and the end chunk (GEND). The codec's streams (BNDY, CONN, GEOM,
// PFLD, CFLD) and the merge tree (MTRE) are opaque here.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "format/gtn_chunk.h"
#include "mesh/mesh_stream.h"

namespace gtn {

// Bounds a reader enforces on header fields (spec: "Limits").
inline constexpr uint64_t kGtnMaxLevels = 65535;
inline constexpr uint64_t kGtnMaxFields = 65535;
inline constexpr uint64_t kGtnMaxComponents = 4096;  // as the level codec

// GHDR writer flag bits: informational; readers ignore them (and any other "unused" bit).
inline constexpr uint8_t kGhdrHasDirectory = 0x01;

struct GtnFileHeader {
  uint8_t writer_flags = 0;
  uint64_t level_count = 0;
  uint64_t points = 0, tets = 0;  // of level 0
  ScalarType coord_type = ScalarType::kFloat64;
  std::vector<FieldDesc> point_fields, cell_fields;
  double bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};  // of level 0
  std::string tool_version, command_line;                   // provenance
  std::vector<std::pair<std::string, std::string>> metadata;
};

struct GtnLevelRecord {
  uint64_t level = 0;
  uint64_t merges = 0;
  double ratio = 0.0;
  uint64_t points = 0, tets = 0, boundary_triangles = 0;
  double bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};
};

struct GtnDirectoryEntry {
  ChunkTag tag;
  uint64_t offset = 0, size = 0;  // of the whole chunk (framing included)
  friend bool operator==(const GtnDirectoryEntry&, const GtnDirectoryEntry&) = default;
};
using GtnDirectory = std::vector<std::vector<GtnDirectoryEntry>>;  // per level, its chunks in file order

struct GtnTrailer {
  uint64_t directory_offset = 0, directory_size = 0;  // 0, 0: no directory
};

std::vector<uint8_t> encodeFileHeader(const GtnFileHeader& h);
std::vector<uint8_t> encodeLevelRecord(const GtnLevelRecord& r);
std::vector<uint8_t> encodeDirectory(const GtnDirectory& d);
std::vector<uint8_t> encodeTrailer(const GtnTrailer& t);

// Decoders: `payload` is the chunk's (decompressed) payload, `offset` the file offset of its first byte
// (for messages; for zstd chunks, offsets point into the decompressed payload and say so).
Status decodeFileHeader(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, GtnFileHeader* h);
Status decodeLevelRecord(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, GtnLevelRecord* r);
Status decodeDirectory(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, uint64_t level_count,
                       GtnDirectory* d);
Status decodeTrailer(std::span<const uint8_t> payload, uint64_t offset, const std::string& what, GtnTrailer* t);

}  // namespace gtn
