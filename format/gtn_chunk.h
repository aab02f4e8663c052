// Chunk framing of the .gtn container (spec/gtn-format.md, sections "File prefix" and "Chunks"):
// the 16-byte file prefix and the checksummed, optionally zstd-compressed chunks that follow it.
// The writer and the reader share these definitions; tests and the conformance generator use them to
// build deliberately malformed files.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mesh/status.h"

namespace gtn {

// 0x8E "GTN" CR LF ^Z LF: not ASCII, not UTF-8; damage by text-mode transfer or truncation shows.
inline constexpr std::array<uint8_t, 8> kGtnMagic = {0x8E, 'G', 'T', 'N', 0x0D, 0x0A, 0x1A, 0x0A};
inline constexpr uint16_t kGtnMajorVersion = 2;
inline constexpr uint16_t kGtnMinorVersion = 0;
// Format 2.0 is a draft until it is released: GHDR names the draft revision its bitstream follows,
// and a reader reads only its own (spec/gtn-format.md, "File header").
inline constexpr uint64_t kGtnDraftRevision = 6;
inline constexpr size_t kGtnPrefixSize = 16;

// Four ASCII letters or digits naming a chunk's type.
struct ChunkTag {
  std::array<char, 4> c{};
  constexpr ChunkTag() = default;
  constexpr explicit ChunkTag(const char (&s)[5]) : c{s[0], s[1], s[2], s[3]} {}
  std::string str() const { return std::string(c.data(), 4); }
  friend bool operator==(const ChunkTag&, const ChunkTag&) = default;
};

inline constexpr ChunkTag kTagFileHeader("GHDR");
inline constexpr ChunkTag kTagLevelHeader("LHDR");
inline constexpr ChunkTag kTagSeam("SEAM");
inline constexpr ChunkTag kTagGrid("GRID");   // a structured piece's one chunk (piece kind 1)
inline constexpr ChunkTag kTagPiece("PIEC");  // an unstructured piece's codec streams (piece kind 0)
inline constexpr ChunkTag kTagMergeTree("MTRE");
inline constexpr ChunkTag kTagDirectory("DIRC");
inline constexpr ChunkTag kTagEnd("GEND");

// Chunk flag bits. Bits 2..7 are reserved: a reader rejects a chunk that sets any of them.
inline constexpr uint8_t kChunkAncillary = 0x01;  // a reader that does not know the type may skip it
inline constexpr uint8_t kChunkZstd = 0x02;       // the payload is one zstd frame of raw_size bytes
inline constexpr uint8_t kChunkReservedMask = 0xFC;

inline constexpr size_t kChunkFixedHeaderSize = 13;  // tag 4, flags 1, stored_size 8
inline constexpr size_t kChunkChecksumSize = 8;
// A zstd payload may declare at most this many raw bytes per stored byte (plus kZstdRawSlack): the
// bound on what a reader allocates for a chunk of a given size.
inline constexpr uint64_t kZstdMaxRatio = 4096;
inline constexpr uint64_t kZstdRawSlack = 4096;
// The end chunk (trailer) has a fixed size: header 13, payload 16 (directory offset, size), checksum 8.
inline constexpr size_t kGtnEndPayloadSize = 16;
inline constexpr size_t kGtnTrailerSize = kChunkFixedHeaderSize + kGtnEndPayloadSize + kChunkChecksumSize;

// The 16-byte prefix: magic, major and minor version (u16 each), low 32 bits of the XXH3-64 of the
// first 12 bytes.
std::array<uint8_t, kGtnPrefixSize> encodeGtnPrefix(uint16_t major = kGtnMajorVersion,
                                                    uint16_t minor = kGtnMinorVersion);
// Checks a prefix: magic (with diagnoses of byte-swapped, text-mode-damaged or foreign files), then the
// major version (kVersionTooNew when newer; kUnsupported for 1.x, a draft that was never released),
// then the prefix checksum. `what` names the file.
Status checkGtnPrefix(std::span<const uint8_t> bytes, const std::string& what, uint16_t* major, uint16_t* minor);

// XXH3-64 (seed 0) of the bytes, as the chunk checksum uses it.
uint64_t gtnChecksum(std::span<const uint8_t> bytes);

// Appends one framed chunk to `out`. With `try_zstd` the payload is compressed at `zstd_level` and
// stored compressed only if that is smaller (counting the 8-byte raw_size) and within kZstdMaxRatio;
// otherwise raw. Deterministic: same input, same bytes.
void appendGtnChunk(std::vector<uint8_t>& out, ChunkTag tag, std::span<const uint8_t> payload, bool ancillary,
                    bool try_zstd, int zstd_level);

// The framing fields of one chunk as read from a file.
struct ChunkHeader {
  ChunkTag tag;
  uint8_t flags = 0;
  uint64_t offset = 0;       // of the chunk's first byte in the file
  uint64_t header_size = 0;  // 13, or 21 with raw_size
  uint64_t stored_size = 0;  // payload bytes as stored
  uint64_t raw_size = 0;     // payload bytes after decompression (= stored_size when not zstd)
  bool ancillary() const { return flags & kChunkAncillary; }
  bool zstd() const { return flags & kChunkZstd; }
  uint64_t totalSize() const { return header_size + stored_size + kChunkChecksumSize; }
};

// Parses a chunk's header from `bytes` (at least kChunkFixedHeaderSize, or 21 when the zstd flag is
// set; *needed tells how many were required when fewer are given). `remaining` is the number of file
// bytes from the chunk's offset to the end of the file, when known (UINT64_MAX otherwise): sizes
// beyond it are reported as truncation before anything is allocated.
Status parseGtnChunkHeader(std::span<const uint8_t> bytes, uint64_t offset, uint64_t remaining, const std::string& what,
                           ChunkHeader* header, size_t* needed);

// Whether a whole chunk's stored checksum matches its bytes (`chunk` as for openGtnChunk).
bool gtnChunkChecksumMatches(const ChunkHeader& header, std::span<const uint8_t> chunk);

// Verifies the checksum of a whole chunk (`chunk` = header bytes, stored payload, checksum) and
// returns its payload, decompressed when the zstd flag is set (exactly raw_size bytes, one frame).
StatusOr<std::vector<uint8_t>> openGtnChunk(const ChunkHeader& header, std::span<const uint8_t> chunk,
                                            const std::string& what);
// The same, taking the chunk's buffer: a payload stored without compression is returned in that
// buffer (moved to its start) rather than copied.
StatusOr<std::vector<uint8_t>> openGtnChunk(const ChunkHeader& header, std::vector<uint8_t>&& chunk,
                                            const std::string& what);

}  // namespace gtn
