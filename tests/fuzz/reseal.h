// Re-seals a mutated .gtn image: recomputes the prefix check and the checksum of every chunk whose
// framing still fits the bytes, in place. A fuzzer's random mutation of a chunk payload then reaches
// the payload parsers and decoders instead of stopping at the checksum. Used by the fuzz target
// fuzz_gtn_sealed.cpp (as a custom mutator) and tested in tests/validate/fuzz_corpus_test.cpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "format/gtn_chunk.h"

namespace gtn::fuzz {

// Returns the number of chunks re-sealed. Bytes after the last chunk that fits are left as they are.
inline size_t resealGtn(uint8_t* data, size_t size) {
  if (size < kGtnPrefixSize) return 0;
  auto store64 = [](uint8_t* p, uint64_t v) {
    for (int i = 0; i < 8; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
  };
  auto load64 = [](const uint8_t* p) {
    uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
    return v;
  };
  const uint64_t prefix_check = gtnChecksum(std::span<const uint8_t>(data, 12));
  for (int i = 0; i < 4; ++i) data[12 + i] = static_cast<uint8_t>(prefix_check >> (8 * i));
  size_t pos = kGtnPrefixSize, sealed = 0;
  while (size - pos >= kChunkFixedHeaderSize) {
    const bool zstd = data[pos + 4] & kChunkZstd;
    const size_t header = zstd ? kChunkFixedHeaderSize + 8 : kChunkFixedHeaderSize;
    if (size - pos < header) break;
    const uint64_t stored = load64(data + pos + 5);
    if (stored > size - pos - header || size - pos - header - stored < kChunkChecksumSize) break;
    const size_t body = header + static_cast<size_t>(stored);
    store64(data + pos + body, gtnChecksum(std::span<const uint8_t>(data + pos, body)));
    pos += body + kChunkChecksumSize;
    ++sealed;
  }
  return sealed;
}

}  // namespace gtn::fuzz
