// Lossless coding of scalar values (coordinates, point and cell fields) against a prediction.
//
// Every value is mapped to an ordered integer "key" of its type's width: floats by their bit
// pattern (negative values bit-inverted, positive ones with the sign bit set, so that key order is
// numeric order), signed integers with their sign bit flipped, unsigned ones as they are. A
// prediction computed in double is rounded to the value's type (non-finite predictions become 0) and
// mapped the same way; the residual is the difference of the keys modulo 2^width, read as a signed
// number. Its magnitude's bit length is coded with an adaptive bit tree whose context is the bit
// length of the previous residual of the same component; then the sign, the two bits below the
// leading one (adaptive) and the remaining bits raw. All of it is integer arithmetic on bit patterns,
// so every platform reproduces the same bits (NaN payloads included).
#pragma once

#include <cstdint>
#include <vector>

#include "codec/range_coder.h"
#include "mesh/tet_mesh.h"

namespace gtn {

int scalarBits(ScalarType type);
uint64_t keyFromRaw(ScalarType type, const uint8_t* p);
void rawFromKey(ScalarType type, uint64_t key, uint8_t* p);
// The prediction `v` rounded to `type` (integers clamped to their range), as a key.
uint64_t keyFromPrediction(ScalarType type, double v);
double doubleFromRaw(ScalarType type, const uint8_t* p);

class ValueCoder {
 public:
  ValueCoder(ScalarType type, uint32_t components);

  ScalarType type() const { return type_; }
  uint32_t components() const { return components_; }

  // Codes component `comp` given the predicted key; returns the actual key (the decoder's result).
  template <class C>
  uint64_t code(C& c, uint32_t comp, uint64_t pred_key, uint64_t actual_key);

 private:
  static constexpr int kTreeBits = 7;      // bucket 0..64
  static constexpr int kContexts = 17;     // previous bucket / 4

  struct Component {
    std::vector<BitTree<kTreeBits>> bucket;  // [context]
    BitModel sign[65];
    BitModel high[65][4];  // the two bits below the leading one, as a 2-bit tree per bucket
    uint32_t last_bucket = 0;
  };

  ScalarType type_;
  uint32_t components_;
  int bits_;
  uint64_t mask_;
  std::vector<Component> comp_;
};

template <class C>
uint64_t ValueCoder::code(C& c, uint32_t comp, uint64_t pred_key, uint64_t actual_key) {
  Component& m = comp_[comp];
  const uint64_t r = (actual_key - pred_key) & mask_;
  const uint64_t half = uint64_t{1} << (bits_ - 1);
  const bool negative = r >= half && r != 0;
  uint64_t mag = negative ? ((~r + 1) & mask_) : r;
  if (negative && mag == 0) mag = half;  // unreachable for widths < 64; keeps -2^63 exact
  uint32_t k = 0;
  if (mag) k = 64 - static_cast<uint32_t>(__builtin_clzll(mag));
  k = m.bucket[m.last_bucket >> 2].code(c, k);
  if (k > static_cast<uint32_t>(bits_)) k = bits_;  // corrupt stream; the decoder fails later
  m.last_bucket = k;
  if (k == 0) return pred_key;
  const uint32_t s = c.bit(m.sign[k], negative ? 1 : 0);
  uint64_t out = 1;
  const int below = static_cast<int>(k) - 1;
  const int high_bits = below < 2 ? below : 2;
  uint32_t node = 1;
  for (int i = 0; i < high_bits; ++i) {
    const uint32_t b = c.bit(m.high[k][node], (mag >> (below - 1 - i)) & 1);
    node = (node << 1) | b;
    out = (out << 1) | b;
  }
  int rest = below - high_bits;
  while (rest > 0) {
    const int n = rest > 16 ? 16 : rest;
    rest -= n;
    const uint32_t v = c.direct(static_cast<uint32_t>((mag >> rest) & ((1u << n) - 1)), n);
    out = (out << n) | v;
  }
  const uint64_t res = s ? ((~out + 1) & mask_) : out;
  return (pred_key + res) & mask_;
}

}  // namespace gtn
