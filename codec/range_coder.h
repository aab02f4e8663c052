// Binary adaptive range coder used by the level codec (LZMA's carry-propagating range coder with
// 16-bit probabilities that mix a fast and a slow adaptation rate), plus uniform "direct" bits.
//
// Byte accounting: the encoder's flush writes exactly the bytes the decoder reads, so a decoder that
// has read past the end of its buffer, or that stops before the end, is looking at a corrupt stream
// (RangeDecoder::finishedCleanly()).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace gtn {

// Adaptation rate, as a multiple of 2^-16, of a model's estimates at its n-th update (n = 0, 1, ...):
// 1/(n + 2) while that exceeds the estimate's final rate, then the final rate (1/16 fast, 1/128 slow).
// The first updates thus average what was seen so far instead of creeping from 1/2, which is what
// small meshes and rarely used contexts pay for.
inline constexpr int kModelWarmup = 126;  // updates after which both rates are final
constexpr std::array<uint16_t, kModelWarmup + 1> modelRates(uint32_t final_div) {
  std::array<uint16_t, kModelWarmup + 1> r{};
  for (uint32_t n = 0; n <= kModelWarmup; ++n)
    r[n] = static_cast<uint16_t>(65536u / (n + 2 < final_div ? n + 2 : final_div));
  return r;
}
inline constexpr auto kFastRate = modelRates(16);
inline constexpr auto kSlowRate = modelRates(128);

// Probability that the next bit is 0, as two 16-bit estimates: one adapting fast (final rate 1/16),
// one slowly (final rate 1/128), both warming up as kFastRate and kSlowRate say.
struct BitModel {
  uint16_t fast = 32768, slow = 32768;
  uint8_t seen = 0;                                             // updates so far, saturating at kModelWarmup
  uint32_t p0() const { return (uint32_t{fast} + slow) >> 1; }  // in [1, 65535]: never 0 or 65536
  void update(uint32_t bit) {
    if (seen < kModelWarmup) [[unlikely]] {
      warmUpdate(bit);
      return;
    }
    // The final rates 4096 and 512 (of 65536) as shifts: the same steps.
    if (bit) {
      fast -= fast >> 4;
      slow -= slow >> 7;
    } else {
      fast += (65536 - fast) >> 4;
      slow += (65536 - slow) >> 7;
    }
  }
  void warmUpdate(uint32_t bit) {
    const uint32_t rf = kFastRate[seen], rs = kSlowRate[seen];
    ++seen;
    // Rounding down the step keeps each estimate inside (0, 65536).
    if (bit) {
      fast -= static_cast<uint16_t>((fast * rf) >> 16);
      slow -= static_cast<uint16_t>((slow * rs) >> 16);
    } else {
      fast += static_cast<uint16_t>(((65536 - fast) * rf) >> 16);
      slow += static_cast<uint16_t>(((65536 - slow) * rs) >> 16);
    }
  }
};

class RangeEncoder {
 public:
  explicit RangeEncoder(std::vector<uint8_t>* out) : out_(out) {}

  void encodeBit(BitModel& m, uint32_t bit) {
    const uint32_t bound = (range_ >> 16) * m.p0();
    if (bit) {
      low_ += bound;
      range_ -= bound;
    } else {
      range_ = bound;
    }
    m.update(bit);
    if (range_ < (1u << 24)) [[unlikely]]
      normalize();
  }
  // `n` (1..16) raw bits of `value`, each equally likely.
  void encodeDirect(uint32_t value, int n) {
    range_ >>= n;
    low_ += uint64_t{value} * range_;
    if (range_ < (1u << 24)) normalize();
  }
  void flush() {
    for (int i = 0; i < 5; ++i) shiftLow();
  }

 private:
  // Out of line, as only about one bit in ten needs it: encodeBit then saves and restores no
  // registers for it (they cost as much as the bit's arithmetic).
  [[gnu::noinline]] void normalize() {
    do {
      range_ <<= 8;
      shiftLow();
    } while (range_ < (1u << 24));
  }
  void shiftLow() {
    if (static_cast<uint32_t>(low_) < 0xFF000000u || (low_ >> 32) != 0) {
      const uint8_t carry = static_cast<uint8_t>(low_ >> 32);
      uint8_t temp = cache_;
      do {
        out_->push_back(static_cast<uint8_t>(temp + carry));
        temp = 0xFF;
      } while (--cache_size_ != 0);
      cache_ = static_cast<uint8_t>(static_cast<uint32_t>(low_) >> 24);
    }
    ++cache_size_;
    low_ = static_cast<uint32_t>(low_) << 8;
  }

  std::vector<uint8_t>* out_;
  uint64_t low_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
  uint8_t cache_ = 0;
  uint64_t cache_size_ = 1;
};

class RangeDecoder {
 public:
  explicit RangeDecoder(std::span<const uint8_t> in) : in_(in) {
    // The encoder's first byte is always 0; anything else is not our stream.
    if (in_.empty() || in_[0] != 0) bad_ = true;
    for (int i = 0; i < 5; ++i) code_ = (code_ << 8) | nextByte();
  }

  [[gnu::always_inline]] uint32_t decodeBit(BitModel& m) {
    const uint32_t bit = decide(range_, code_, m);
    if (range_ < (1u << 24)) [[unlikely]]
      normalize();
    return bit;
  }
  // The symbol of a BitTree<kBits> (its models m), the bits decoded as decodeBit does with the
  // coder's state in locals: the model updates cannot then make it reload and store it each bit.
  template <int kBits>
  uint32_t decodeTree(BitModel* m) {
    uint32_t range = range_, code = code_, node = 1;
    for (int i = 0; i < kBits; ++i) {
      const uint32_t bit = decide(range, code, m[node]);
      if (range < (1u << 24)) [[unlikely]] {
        range_ = range;
        code_ = code;
        normalize();
        range = range_;
        code = code_;
      }
      node = (node << 1) | bit;
    }
    range_ = range;
    code_ = code;
    return node - (1u << kBits);
  }
  uint32_t decodeDirect(int n) {
    range_ >>= n;
    uint32_t v = code_ / range_;
    if (v >> n) {  // only a corrupt stream gets here
      v = (1u << n) - 1;
      bad_ = true;
    }
    code_ -= v * range_;
    normalize();
    return v;
  }
  // True while no byte past the end was requested and the stream started correctly.
  bool ok() const { return !bad_ && overrun_ == 0; }
  // A symbol decoded to a value the stream cannot hold (only a corrupt stream's).
  void markCorrupt() { bad_ = true; }
  // After the last symbol: every byte consumed, none past the end.
  bool finishedCleanly() const { return ok() && pos_ == in_.size(); }
  size_t position() const { return pos_; }

 private:
  uint8_t nextByte() {
    if (pos_ < in_.size()) return in_[pos_++];
    ++overrun_;
    return 0;
  }
  // One binary decision against model m: narrows the range, moves the code, updates the model.
  [[gnu::always_inline]] static uint32_t decide(uint32_t& range, uint32_t& code, BitModel& m) {
    const uint32_t bound = (range >> 16) * m.p0();
    uint32_t bit;
    if (code < bound) {
      range = bound;
      bit = 0;
    } else {
      code -= bound;
      range -= bound;
      bit = 1;
    }
    m.update(bit);
    return bit;
  }
  // Out of line, as in the encoder: most bits need none, and decodeBit is then small enough to
  // inline at its every call.
  [[gnu::noinline]] void normalize() {
    while (range_ < (1u << 24)) {
      range_ <<= 8;
      code_ = (code_ << 8) | nextByte();
    }
  }

  std::span<const uint8_t> in_;
  size_t pos_ = 0;
  uint64_t overrun_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
  uint32_t code_ = 0;
  bool bad_ = false;
};

// The number of bits of v without its leading zeros (0 for 0).
inline int bitLength(uint64_t v) { return v ? 64 - __builtin_clzll(v) : 0; }

// One interface over both directions so that the encoder and the decoder run the same code: the
// encoder passes the value to write and gets it back, the decoder ignores the argument and gets the
// decoded value.
template <bool kEncode>
class EntropyCoder;

template <>
class EntropyCoder<true> {
 public:
  static constexpr bool kEncoding = true;
  explicit EntropyCoder(std::vector<uint8_t>* out) : enc_(out) {}
  uint32_t bit(BitModel& m, uint32_t b) {
    enc_.encodeBit(m, b);
    return b;
  }
  // `symbol` through the BitTree<kBits> whose models are m.
  template <int kBits>
  uint32_t tree(BitModel* m, uint32_t symbol) {
    uint32_t node = 1;
    for (int i = kBits - 1; i >= 0; --i) node = (node << 1) | bit(m[node], (symbol >> i) & 1);
    return node - (1u << kBits);
  }
  // `n` (0..32) raw bits.
  uint32_t direct(uint32_t v, int n) {
    if (n > 16) {
      enc_.encodeDirect(v >> 16, n - 16);
      enc_.encodeDirect(v & 0xFFFF, 16);
    } else if (n > 0) {
      enc_.encodeDirect(v, n);
    }
    return v;
  }
  void finish() { enc_.flush(); }
  bool ok() const { return true; }
  void markCorrupt() {}

 private:
  RangeEncoder enc_;
};

template <>
class EntropyCoder<false> {
 public:
  static constexpr bool kEncoding = false;
  explicit EntropyCoder(std::span<const uint8_t> in) : dec_(in) {}
  uint32_t bit(BitModel& m, uint32_t) { return dec_.decodeBit(m); }
  template <int kBits>
  uint32_t tree(BitModel* m, uint32_t) {
    return dec_.decodeTree<kBits>(m);
  }
  uint32_t direct(uint32_t, int n) {
    if (n > 16) {
      const uint32_t hi = dec_.decodeDirect(n - 16);
      return (hi << 16) | dec_.decodeDirect(16);
    }
    return n > 0 ? dec_.decodeDirect(n) : 0;
  }
  void finish() {}
  bool ok() const { return dec_.ok(); }
  void markCorrupt() { dec_.markCorrupt(); }
  bool finishedCleanly() const { return dec_.finishedCleanly(); }

 private:
  RangeDecoder dec_;
};

// Symbols of `kBits` bits coded most significant bit first through a binary tree of models.
template <int kBits>
struct BitTree {
  BitModel m[1 << kBits];
  template <class C>
  uint32_t code(C& c, uint32_t symbol) {
    return c.template tree<kBits>(m, symbol);
  }
};

}  // namespace gtn
