#include "format/gtn_chunk.h"

#include <xxhash.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>

namespace gtn {

namespace {
uint64_t loadU64(const uint8_t* p) {
  uint64_t r = 0;
  for (int i = 7; i >= 0; --i) r = (r << 8) | p[i];
  return r;
}
void storeU64(uint8_t* p, uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
std::string at(const std::string& what, uint64_t offset) {
  return what + ": byte offset " + std::to_string(offset) + ": ";
}
bool validTagChar(char ch) { return (ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9'); }
std::string printableTag(const ChunkTag& tag) {
  std::string s;
  for (char ch : tag.c) {
    if (validTagChar(ch)) {
      s += ch;
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", static_cast<unsigned char>(ch));
      s += buf;
    }
  }
  return s;
}
}  // namespace

uint64_t gtnChecksum(std::span<const uint8_t> bytes) { return XXH3_64bits(bytes.data(), bytes.size()); }

std::array<uint8_t, kGtnPrefixSize> encodeGtnPrefix(uint16_t major, uint16_t minor) {
  std::array<uint8_t, kGtnPrefixSize> p{};
  std::copy(kGtnMagic.begin(), kGtnMagic.end(), p.begin());
  p[8] = static_cast<uint8_t>(major);
  p[9] = static_cast<uint8_t>(major >> 8);
  p[10] = static_cast<uint8_t>(minor);
  p[11] = static_cast<uint8_t>(minor >> 8);
  const uint32_t check = static_cast<uint32_t>(XXH3_64bits(p.data(), 12));
  for (int i = 0; i < 4; ++i) p[12 + i] = static_cast<uint8_t>(check >> (8 * i));
  return p;
}

Status checkGtnPrefix(std::span<const uint8_t> b, const std::string& what, uint16_t* major, uint16_t* minor) {
  const size_t n = std::min<size_t>(b.size(), 8);
  if (!std::equal(b.begin(), b.begin() + n, kGtnMagic.begin())) {
    if (b.size() >= 4 && b[0] == 0x0E && b[1] == 'G' && b[2] == 'T' && b[3] == 'N')
      return Status(StatusCode::kNotOurFile,
                    what +
                        ": byte offset 0: bad magic: the first byte lost its high bit (0x0E instead of 0x8E); "
                        "the file went through a 7-bit channel");
    if (b.size() >= 4 && b[0] == 0x8E && b[1] == 'G' && b[2] == 'T' && b[3] == 'N')
      return Status(StatusCode::kInvalidData,
                    what +
                        ": byte offset 4: bad magic: the CR LF ^Z LF bytes after \"GTN\" were altered; "
                        "the file was probably transferred in text mode");
    return Status(StatusCode::kNotOurFile,
                  what + ": byte offset 0: bad magic: not a .gtn file (expected 8E 47 54 4E 0D 0A 1A 0A)");
  }
  if (b.size() < kGtnPrefixSize)
    return invalidData(at(what, b.size()) + "truncated: the file ends inside the 16-byte .gtn prefix (" +
                       std::to_string(b.size()) + " bytes)");
  *major = static_cast<uint16_t>(b[8] | (b[9] << 8));
  *minor = static_cast<uint16_t>(b[10] | (b[11] << 8));
  if (*major > kGtnMajorVersion)
    return Status(StatusCode::kVersionTooNew, at(what, 8) + "format version " + std::to_string(*major) + "." +
                                                  std::to_string(*minor) + " is newer than this reader supports (" +
                                                  std::to_string(kGtnMajorVersion) + ".x); use a newer gtn to read it");
  if (*major == 0) return invalidData(at(what, 8) + "format major version 0 does not exist");
  if (*major < kGtnMajorVersion)
    return Status(StatusCode::kUnsupported, at(what, 8) + "format version " + std::to_string(*major) + "." +
                                                std::to_string(*minor) + " is not read by this gtn (it reads " +
                                                std::to_string(kGtnMajorVersion) +
                                                ".x; 1.x was never released): convert the source mesh again");
  const uint32_t check = static_cast<uint32_t>(XXH3_64bits(b.data(), 12));
  uint32_t stored = 0;
  for (int i = 3; i >= 0; --i) stored = (stored << 8) | b[12 + i];
  if (check != stored) return invalidData(at(what, 12) + "prefix checksum mismatch: the version bytes are corrupt");
  return Status::ok();
}

void appendGtnChunk(std::vector<uint8_t>& out, ChunkTag tag, std::span<const uint8_t> payload, bool ancillary,
                    bool try_zstd, int zstd_level) {
  std::vector<uint8_t> compressed;
  bool use_zstd = false;
  if (try_zstd && payload.size() > 16) {
    compressed.resize(ZSTD_compressBound(payload.size()));
    ZSTD_CCtx* cctx = ZSTD_createCCtx();
    ZSTD_CCtx_setParameter(cctx, ZSTD_c_compressionLevel, zstd_level);
    ZSTD_CCtx_setParameter(cctx, ZSTD_c_contentSizeFlag, 1);
    ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 0);  // the chunk checksum covers it
    const size_t r = ZSTD_compress2(cctx, compressed.data(), compressed.size(), payload.data(), payload.size());
    ZSTD_freeCCtx(cctx);
    if (!ZSTD_isError(r)) {
      compressed.resize(r);
      use_zstd = r + 8 < payload.size() && payload.size() <= kZstdMaxRatio * r + kZstdRawSlack;
    }
  }
  const std::span<const uint8_t> stored = use_zstd ? std::span<const uint8_t>(compressed) : payload;
  const size_t start = out.size();
  out.insert(out.end(), tag.c.begin(), tag.c.end());
  out.push_back(static_cast<uint8_t>((ancillary ? kChunkAncillary : 0) | (use_zstd ? kChunkZstd : 0)));
  uint8_t size_bytes[8];
  storeU64(size_bytes, stored.size());
  out.insert(out.end(), size_bytes, size_bytes + 8);
  if (use_zstd) {
    storeU64(size_bytes, payload.size());
    out.insert(out.end(), size_bytes, size_bytes + 8);
  }
  out.insert(out.end(), stored.begin(), stored.end());
  storeU64(size_bytes, XXH3_64bits(out.data() + start, out.size() - start));
  out.insert(out.end(), size_bytes, size_bytes + 8);
}

Status parseGtnChunkHeader(std::span<const uint8_t> b, uint64_t offset, uint64_t remaining, const std::string& what,
                           ChunkHeader* h, size_t* needed) {
  *needed = kChunkFixedHeaderSize;
  if (b.size() < kChunkFixedHeaderSize)
    return invalidData(at(what, offset) + "truncated: the file ends inside a chunk header (" +
                       std::to_string(b.size()) + " of 13 bytes)");
  h->offset = offset;
  std::memcpy(h->tag.c.data(), b.data(), 4);
  for (char ch : h->tag.c)
    if (!validTagChar(ch))
      return invalidData(at(what, offset) + "invalid chunk type '" + printableTag(h->tag) +
                         "' (types are four ASCII letters or digits): corrupt data");
  h->flags = b[4];
  if (h->flags & kChunkReservedMask)
    return invalidData(at(what, offset + 4) + "chunk '" + h->tag.str() + "' sets reserved flag bits (flags 0x" + [&] {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%02X", h->flags);
      return std::string(buf);
    }() + ")");
  h->stored_size = loadU64(b.data() + 5);
  h->header_size = kChunkFixedHeaderSize;
  if (h->zstd()) {
    *needed = kChunkFixedHeaderSize + 8;
    if (b.size() < *needed)
      return invalidData(at(what, offset) + "truncated: the file ends inside a chunk header (" +
                         std::to_string(b.size()) + " of 21 bytes)");
    h->header_size = *needed;
    h->raw_size = loadU64(b.data() + 13);
  } else {
    h->raw_size = h->stored_size;
  }
  const uint64_t after_header = remaining == UINT64_MAX ? UINT64_MAX : remaining - h->header_size;
  if (h->stored_size > after_header || after_header - h->stored_size < kChunkChecksumSize)
    return invalidData(at(what, offset) + "truncated: chunk '" + h->tag.str() + "' declares " +
                       std::to_string(h->stored_size) + " payload bytes plus an 8-byte checksum but only " +
                       std::to_string(after_header) + " bytes remain in the file");
  if (h->zstd() && (h->raw_size > kZstdMaxRatio * h->stored_size + kZstdRawSlack))
    return invalidData(at(what, offset + 13) + "chunk '" + h->tag.str() + "' declares " + std::to_string(h->raw_size) +
                       " decompressed bytes from " + std::to_string(h->stored_size) +
                       " stored bytes, beyond the format's bound");
  return Status::ok();
}

bool gtnChunkChecksumMatches(const ChunkHeader& h, std::span<const uint8_t> chunk) {
  const size_t body = h.header_size + h.stored_size;
  if (chunk.size() != h.totalSize()) return false;
  return XXH3_64bits(chunk.data(), body) == loadU64(chunk.data() + body);
}

StatusOr<std::vector<uint8_t>> openGtnChunk(const ChunkHeader& h, std::span<const uint8_t> chunk,
                                            const std::string& what) {
  if (chunk.size() != h.totalSize()) return invalidData(at(what, h.offset) + "internal: chunk buffer size mismatch");
  const size_t body = h.header_size + h.stored_size;
  const uint64_t expected = loadU64(chunk.data() + body);
  if (XXH3_64bits(chunk.data(), body) != expected)
    return invalidData(at(what, h.offset) + "checksum mismatch in chunk '" + h.tag.str() + "' (" +
                       std::to_string(h.totalSize()) + " bytes): the data is corrupt");
  const std::span<const uint8_t> stored = chunk.subspan(h.header_size, h.stored_size);
  if (!h.zstd()) return std::vector<uint8_t>(stored.begin(), stored.end());

  // Decompress incrementally so that memory follows what the frame really produces, never more than
  // the declared raw_size.
  std::vector<uint8_t> out(std::min<uint64_t>(h.raw_size, std::max<uint64_t>(4 * h.stored_size, 1 << 16)));
  ZSTD_DCtx* dctx = ZSTD_createDCtx();
  ZSTD_inBuffer in{stored.data(), stored.size(), 0};
  ZSTD_outBuffer ob{out.data(), out.size(), 0};
  const std::string where = at(what, h.offset + h.header_size);
  Status st;
  for (;;) {
    const size_t r = ZSTD_decompressStream(dctx, &ob, &in);
    if (ZSTD_isError(r)) {
      st = invalidData(where + "zstd payload of chunk '" + h.tag.str() + "' is corrupt: " + ZSTD_getErrorName(r));
      break;
    }
    if (r == 0) {  // frame complete
      if (in.pos != in.size)
        st = invalidData(where + "chunk '" + h.tag.str() + "' has " + std::to_string(in.size - in.pos) +
                         " bytes after its zstd frame");
      else if (ob.pos != h.raw_size)
        st = invalidData(where + "chunk '" + h.tag.str() + "' decompresses to " + std::to_string(ob.pos) +
                         " bytes, not the declared " + std::to_string(h.raw_size));
      break;
    }
    if (ob.pos == ob.size) {
      if (ob.size >= h.raw_size) {
        st = invalidData(where + "chunk '" + h.tag.str() + "' decompresses to more than the declared " +
                         std::to_string(h.raw_size) + " bytes");
        break;
      }
      out.resize(std::min<uint64_t>(h.raw_size, 2 * out.size()));
      ob.dst = out.data();
      ob.size = out.size();
    } else if (in.pos == in.size) {
      st = invalidData(where + "zstd payload of chunk '" + h.tag.str() + "' is truncated");
      break;
    }
  }
  ZSTD_freeDCtx(dctx);
  GTN_RETURN_IF_ERROR(st);
  out.resize(ob.pos);
  return out;
}

StatusOr<std::vector<uint8_t>> openGtnChunk(const ChunkHeader& h, std::vector<uint8_t>&& chunk,
                                            const std::string& what) {
  if (h.zstd() || chunk.size() != h.totalSize()) return openGtnChunk(h, std::span<const uint8_t>(chunk), what);
  if (!gtnChunkChecksumMatches(h, chunk))
    return invalidData(at(what, h.offset) + "checksum mismatch in chunk '" + h.tag.str() + "' (" +
                       std::to_string(h.totalSize()) + " bytes): the data is corrupt");
  std::vector<uint8_t> out = std::move(chunk);
  std::memmove(out.data(), out.data() + h.header_size, h.stored_size);
  out.resize(h.stored_size);
  return out;
}

}  // namespace gtn
