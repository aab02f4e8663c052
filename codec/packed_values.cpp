#include "codec/packed_values.h"

#include <algorithm>
#include <cstring>

namespace gtn {

namespace {

// The smallest LZMA2 dictionary property whose size holds `bytes` (at least 4 KiB), at most
// kMaxPackedDictProperty. Property p stands for (2 | (p & 1)) << (p / 2 + 11) bytes.
uint8_t dictProperty(uint64_t bytes) {
  uint8_t p = 0;
  while (p < kMaxPackedDictProperty && lzma2DictSize(p) < bytes) ++p;
  return p;
}

// The block-by-block byte planes of `count` items (kLayoutPlanes), or the items themselves.
std::vector<uint8_t> arrange(const uint8_t* items, size_t count, size_t item_bytes, size_t value_size, uint8_t layout) {
  std::vector<uint8_t> out(items, items + count * item_bytes);
  if (layout == kLayoutItems) return out;
  const size_t block = packedBlockItems(item_bytes), comps = item_bytes / value_size;
  for (size_t first = 0; first < count; first += block) {
    const size_t n = std::min(block, count - first);
    uint8_t* o = &out[first * item_bytes];
    const uint8_t* in = items + first * item_bytes;
    for (size_t c = 0; c < comps; ++c)
      for (size_t b = 0; b < value_size; ++b)
        for (size_t i = 0; i < n; ++i) *o++ = in[i * item_bytes + c * value_size + b];
  }
  return out;
}

// Raw LZMA2 of `data` with the dictionary property `dict`; empty on failure. Values of 4 or 8 bytes
// laid out as items get lp and pb of their alignment.
std::vector<uint8_t> lzma2(const std::vector<uint8_t>& data, uint32_t preset, uint8_t dict, size_t align) {
  lzma_options_lzma opt;
  if (lzma_lzma_preset(&opt, preset)) return {};
  opt.dict_size = static_cast<uint32_t>(lzma2DictSize(dict));
  if (align == 4 || align == 8) {
    opt.lc = 0;
    opt.lp = align == 4 ? 2 : 3;
    opt.pb = opt.lp;
  }
  lzma_filter filters[2] = {{LZMA_FILTER_LZMA2, &opt}, {LZMA_VLI_UNKNOWN, nullptr}};
  std::vector<uint8_t> out(lzma_raw_encoder_memusage(filters) == UINT64_MAX ? 0
                                                                            : data.size() + data.size() / 16 + 4096);
  size_t pos = 0;
  if (out.empty() ||
      lzma_raw_buffer_encode(filters, nullptr, data.data(), data.size(), out.data(), &pos, out.size()) != LZMA_OK)
    return {};
  out.resize(pos);
  return out;
}

}  // namespace

uint64_t lzma2DictSize(uint8_t property) {
  return property >= 40 ? 0xFFFFFFFFu : uint64_t{2u | (property & 1u)} << (property / 2 + 11);
}

std::vector<uint8_t> splitStream(const std::vector<uint8_t>& range_part, const std::vector<uint8_t>& packed_items) {
  std::vector<uint8_t> out = {kSplitFormByte, packed_items[1], packed_items[2]};
  for (uint64_t n = range_part.size();; n >>= 7) {
    out.push_back(static_cast<uint8_t>((n & 0x7F) | (n >= 0x80 ? 0x80 : 0)));
    if (n < 0x80) break;
  }
  out.insert(out.end(), range_part.begin(), range_part.end());
  out.insert(out.end(), packed_items.begin() + kPackedHeaderBytes, packed_items.end());
  return out;
}

bool splitParts(std::span<const uint8_t> stream, std::span<const uint8_t>* range_part, std::vector<uint8_t>* packed) {
  if (stream.size() < kPackedHeaderBytes || stream[0] != kSplitFormByte) return false;
  uint64_t length = 0;
  size_t at = kPackedHeaderBytes;
  for (int shift = 0;; shift += 7) {
    if (at >= stream.size() || shift > 56) return false;
    const uint8_t b = stream[at++];
    length |= uint64_t{b & 0x7Fu} << shift;
    if (!(b & 0x80)) break;
  }
  if (length > stream.size() - at) return false;
  *range_part = stream.subspan(at, length);
  packed->assign({kPackedFormByte, stream[1], stream[2]});
  packed->insert(packed->end(), stream.begin() + at + length, stream.end());
  return true;
}

std::vector<uint8_t> packValues(const uint8_t* items, size_t count, size_t item_bytes, size_t value_size, size_t limit,
                                bool items_layout_only) {
  std::vector<uint8_t> best;
  if (item_bytes == 0) return best;
  const uint8_t dict = dictProperty(uint64_t{count} * item_bytes);
  // Each layout's bytes, and a quick estimate of its packed size: preset 1 on at most the first 256 KiB,
  // scaled to the whole. Only a layout that this estimate already puts below the limit, and within
  // 3% of the best estimate, is packed at full strength (preset 9, where the encoder's time goes):
  // LZMA2 packs floating-point arrays only a few percent smaller at preset 9 than at preset 1.
  struct Candidate {
    uint8_t layout;
    std::vector<uint8_t> data;
    size_t align;
    double estimate = 0;
  };
  std::vector<Candidate> candidates;
  for (const uint8_t layout : {kLayoutItems, kLayoutPlanes}) {
    if (layout == kLayoutPlanes && (value_size == 1 || items_layout_only)) continue;  // the same bytes
    Candidate c{layout, arrange(items, count, item_bytes, value_size, layout),
                layout == kLayoutItems && item_bytes == value_size ? value_size : 0};
    if (limit > 0) {
      const size_t prefix = std::min<size_t>(c.data.size(), size_t{1} << 18);
      const std::vector<uint8_t> quick = lzma2(
          std::vector<uint8_t>(c.data.begin(), c.data.begin() + static_cast<std::ptrdiff_t>(prefix)), 1, dict, c.align);
      if (quick.empty()) continue;
      c.estimate = static_cast<double>(quick.size()) * static_cast<double>(c.data.size()) /
                   static_cast<double>(std::max<size_t>(prefix, 1));
      if (c.estimate > static_cast<double>(limit)) continue;
    }
    candidates.push_back(std::move(c));
  }
  double lowest = 0;
  for (size_t i = 0; i < candidates.size(); ++i)
    lowest = i == 0 ? candidates[i].estimate : std::min(lowest, candidates[i].estimate);
  for (const Candidate& c : candidates) {
    if (c.estimate > 1.03 * lowest) continue;
    std::vector<uint8_t> packed = lzma2(c.data, 9, dict, c.align);
    if (packed.empty()) continue;
    if (best.empty() || packed.size() + kPackedHeaderBytes < best.size()) {
      best = {kPackedFormByte, c.layout, dict};
      best.insert(best.end(), packed.begin(), packed.end());
    }
  }
  return best;
}

PackedReader::~PackedReader() {
  if (open_) lzma_end(&strm_);
}

Status PackedReader::open(std::span<const uint8_t> stream, uint64_t count, size_t item_bytes, size_t value_size,
                          const std::string& what, bool exact) {
  what_ = what;
  exact_ = exact;
  if (stream.size() < kPackedHeaderBytes || stream[0] != kPackedFormByte)
    return invalidData(what + ": packed stream shorter than its 3-byte header");
  layout_ = stream[1];
  if (layout_ != kLayoutItems && (layout_ != kLayoutPlanes || !exact))
    return invalidData(what + ": packed stream declares unknown layout " + std::to_string(layout_));
  const uint8_t dict = stream[2];
  // The dictionary bounds what the decoder allocates: at most 64 MiB, and no larger than the
  // smallest property that holds every item (what an encoder declares).
  const uint64_t bytes = count * item_bytes;
  if (item_bytes != 0 && count > UINT64_MAX / item_bytes) return invalidData(what + ": packed stream too large");
  if (dict > kMaxPackedDictProperty || (dict > 0 && lzma2DictSize(dict - 1) >= bytes))
    return invalidData(what + ": packed stream declares an LZMA2 dictionary property of " + std::to_string(dict) +
                       ", larger than its " + std::to_string(bytes) + " bytes of values need");
  lzma_options_lzma opt{};
  opt.dict_size = static_cast<uint32_t>(std::max<uint64_t>(lzma2DictSize(dict), LZMA_DICT_SIZE_MIN));
  lzma_filter filters[2] = {{LZMA_FILTER_LZMA2, &opt}, {LZMA_VLI_UNKNOWN, nullptr}};
  if (lzma_raw_decoder(&strm_, filters) != LZMA_OK) return invalidData(what + ": cannot start the LZMA2 decoder");
  open_ = true;
  in_ = stream.subspan(kPackedHeaderBytes);
  strm_.next_in = in_.data();
  strm_.avail_in = in_.size();
  count_ = count;
  item_bytes_ = item_bytes;
  value_size_ = value_size;
  block_items_ = packedBlockItems(item_bytes);
  block_.resize(std::min<uint64_t>(count, block_items_) * item_bytes);
  if (layout_ == kLayoutPlanes) items_.resize(block_.size());
  return Status::ok();
}

bool PackedReader::fillBlock() {
  const size_t n = static_cast<size_t>(std::min<uint64_t>(block_items_, count_ - done_));
  const size_t want = n * item_bytes_;
  strm_.next_out = block_.data();
  strm_.avail_out = want;
  while (strm_.avail_out > 0) {
    const lzma_ret r = lzma_code(&strm_, LZMA_RUN);
    if (r == LZMA_STREAM_END) ended_ = true;
    if (r == LZMA_STREAM_END && strm_.avail_out > 0 && !exact_) {
      // At most `count` items: those that the stream holds, whole.
      const size_t got = want - strm_.avail_out;
      if (got % item_bytes_ != 0) {
        error_ = what_ + ": packed stream ends inside a value";
        return false;
      }
      if (got == 0) {
        error_ = what_ + ": more values read than the packed stream holds";
        return false;
      }
      in_block_ = got / item_bytes_;
      at_ = 0;
      return true;
    }
    if (r == LZMA_STREAM_END && strm_.avail_out > 0) {
      error_ = what_ + ": packed stream ends after " + std::to_string(done_ * item_bytes_ + want - strm_.avail_out) +
               " of " + std::to_string(count_ * item_bytes_) + " bytes of values";
      return false;
    }
    if (r != LZMA_OK && r != LZMA_STREAM_END) {
      error_ = what_ +
               (r == LZMA_BUF_ERROR ? ": packed stream is truncated" : ": packed stream is corrupt (LZMA2 data error)");
      return false;
    }
  }
  if (layout_ == kLayoutPlanes) {
    const uint8_t* in = block_.data();
    const size_t comps = item_bytes_ / value_size_;
    for (size_t c = 0; c < comps; ++c)
      for (size_t b = 0; b < value_size_; ++b)
        for (size_t i = 0; i < n; ++i) items_[i * item_bytes_ + c * value_size_ + b] = *in++;
  }
  in_block_ = n;
  at_ = 0;
  return true;
}

const uint8_t* PackedReader::next() {
  if (!open_ || !error_.empty()) return nullptr;
  if (done_ >= count_) {
    error_ = what_ + ": more values read than the packed stream holds";
    return nullptr;
  }
  if (at_ == in_block_ && (ended_ || !fillBlock())) {
    if (error_.empty()) error_ = what_ + ": more values read than the packed stream holds";
    return nullptr;
  }
  const uint8_t* item = (layout_ == kLayoutPlanes ? items_.data() : block_.data()) + at_ * item_bytes_;
  ++at_;
  ++done_;
  return item;
}

Status PackedReader::finish() {
  if (!error_.empty()) return invalidData(error_);
  if (exact_ && done_ != count_)
    return invalidData(what_ + ": " + std::to_string(done_) + " of the packed stream's " + std::to_string(count_) +
                       " items were read");
  if (at_ != in_block_) return invalidData(what_ + ": the packed stream holds more values than were read");
  if (!ended_) {
    // The LZMA2 end marker must follow the last value.
    uint8_t extra = 0;
    strm_.next_out = &extra;
    strm_.avail_out = 1;
    const lzma_ret r = lzma_code(&strm_, LZMA_RUN);
    if (r != LZMA_STREAM_END || strm_.avail_out == 0)
      return invalidData(what_ + ": the packed stream holds more values than were read, or lacks its end marker");
    ended_ = true;
  }
  if (strm_.avail_in != 0) return invalidData(what_ + ": packed stream has bytes after its values");
  return Status::ok();
}

}  // namespace gtn
