// The packed form of a value stream (GEOM, PFLD, CFLD; spec section 10.2.1): the stream's values in
// decoding order, compressed by LZMA2, instead of predicted and range coded. It is the fallback for
// values that the predictions do not help: a field of a few thousand distinct levels scattered over
// the mesh, noise. The encoder codes every stream both ways where the packed form may win and keeps
// the smaller, so a stream never costs more than a general-purpose compressor of its values in
// decoding order.
//
// Stream layout: byte 0 = kPackedFormByte (a range-coded stream starts with 0), byte 1 = layout
// (kLayoutItems: the items as stored, little-endian, one after another; kLayoutPlanes: per block,
// for each component, for each byte of the value from the least significant, that byte of every
// item of the block), byte 2 = the LZMA2 dictionary-size property, then one raw LZMA2 stream that
// decodes to exactly count x item_bytes bytes, in blocks of packedBlockItems(item_bytes) items.
#pragma once

#include <lzma.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "mesh/tet_mesh.h"

namespace gtn {

inline constexpr uint8_t kPackedFormByte = 1;
// A CFLD stream in split form: its symbols range coded, the values it escapes packed (layout 0).
inline constexpr uint8_t kSplitFormByte = 2;
inline constexpr uint8_t kLayoutItems = 0;
inline constexpr uint8_t kLayoutPlanes = 1;
inline constexpr size_t kPackedHeaderBytes = 3;
// The largest dictionary a decoder accepts (LZMA2 property 28, 64 MiB: xz -9's).
inline constexpr uint8_t kMaxPackedDictProperty = 28;
// The dictionary size of LZMA2 property p < 40: (2 | (p & 1)) << (p / 2 + 11) bytes.
uint64_t lzma2DictSize(uint8_t property);

// Items per block: as many as fit in 64 KiB, at least one. A decoder holds one block.
inline size_t packedBlockItems(size_t item_bytes) { return item_bytes >= 65536 ? 1 : 65536 / item_bytes; }

// Whether `stream` is in packed form, or in split form (its first byte says so).
inline bool isPackedStream(std::span<const uint8_t> stream) { return !stream.empty() && stream[0] == kPackedFormByte; }
inline bool isSplitStream(std::span<const uint8_t> stream) { return !stream.empty() && stream[0] == kSplitFormByte; }

// A split-form stream: the header, the range-coded part's length as a varint, that part, then the
// packed items (`packed_items`: packValues's output with layout 0, whose header is replaced).
std::vector<uint8_t> splitStream(const std::vector<uint8_t>& range_part, const std::vector<uint8_t>& packed_items);
// The range-coded part of a split stream and the stream that the PackedReader opens (the header
// again, then the LZMA2 data); false when the length is malformed or beyond the stream.
bool splitParts(std::span<const uint8_t> stream, std::span<const uint8_t>* range_part, std::vector<uint8_t>* packed);

// `count` items of `item_bytes` bytes (values of `value_size` bytes) in packed form, in the layout that
// packs smaller (LZMA2 at preset 9). When `limit` is nonzero, a layout whose quick estimate (preset
// 1) is not below `limit`, or is 3% above the other layout's, is not packed at full strength; empty when none is.
std::vector<uint8_t> packValues(const uint8_t* items, size_t count, size_t item_bytes, size_t value_size,
                                size_t limit = 0, bool items_layout_only = false);

// Reads the items of a packed stream one at a time, a block at a time, in bounded memory: the block
// (64 KiB) and LZMA2's dictionary, which the stream declares and which must not exceed what its
// items need (nor 64 MiB).
class PackedReader {
 public:
  PackedReader() = default;
  PackedReader(const PackedReader&) = delete;
  PackedReader& operator=(const PackedReader&) = delete;
  ~PackedReader();

  // Checks the header; `what` names the stream in messages. `exact`: the stream holds exactly `count`
  // items; else at most `count`, as many as are read (the escaped values of a split stream).
  Status open(std::span<const uint8_t> stream, uint64_t count, size_t item_bytes, size_t value_size,
              const std::string& what, bool exact = true);
  // The next item (item_bytes bytes), or null when the stream is corrupt or holds no more (error()
  // says why).
  const uint8_t* next();
  // After the last item: whether the LZMA2 stream ended there, with no byte left over.
  Status finish();
  const std::string& error() const { return error_; }
  bool isOpen() const { return open_; }

 private:
  bool fillBlock();
  std::span<const uint8_t> in_;
  lzma_stream strm_ = LZMA_STREAM_INIT;
  bool open_ = false, exact_ = true, ended_ = false;
  uint8_t layout_ = 0;
  uint64_t count_ = 0, done_ = 0;
  size_t item_bytes_ = 0, value_size_ = 0, block_items_ = 0, at_ = 0, in_block_ = 0;
  std::vector<uint8_t> block_, items_;
  std::string what_, error_;
};

}  // namespace gtn
