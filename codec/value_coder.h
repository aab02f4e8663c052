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
//
// A component whose values all end in s zero bits (a float64 array that holds float32 values ends in
// 29 or more, small integers stored as floats in many more) is coded with s as its shift: keys and
// predictions lose their s low bits, which the decoder restores. When only most values end so (sums of
// float32 values kept in doubles, with a few full doubles among them; exact zeros among computed
// values), a bit per value says which do not, and those are coded whole. A float component whose values are
// mostly decimals of at most e places (what text formats hold: 0.0260146, or 5.67709 printed as
// 5.6770899999999997) is coded in decimal form: a bit per value says whether it is one, and such a
// value is coded as the integer n = v * 10^e, from which IEEE division restores v = n / 10^e bit for
// bit; the others (a mesh generator's own points among the input's, say) as floats, with their own
// models. A float64 component whose values are mostly float32 values printed with p digits and read
// back (0.2f printed "%.15g" is 0.200000002980232) is coded in printed-single form: such a value as
// its float32 value, the others as float64, behind the same per-value bit (spec section 10.2). A
// component of few distinct values (a lattice's coordinates, a field of a few levels) is coded in
// table form: its distinct values once, ascending, then each value as its place in that table.
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "codec/range_coder.h"
#include "mesh/tet_mesh.h"

namespace gtn {

// Conversions between values, their ordered integer keys and doubles (inline: the level codec
// calls them for every coordinate and field value).
namespace value_detail {
template <class T>
inline T loadRaw(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
template <class T>
inline void storeRaw(uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof(T));
}
// Rounds to the nearest integer and clamps to [lo, hi] without undefined conversions.
inline double clampRound(double v, double lo, double hi) {
  if (!(v == v)) return 0.0;
  v = std::nearbyint(v);
  if (v < lo) return lo;
  if (v > hi) return hi;
  return v;
}
}  // namespace value_detail

inline int scalarBits(ScalarType type) { return static_cast<int>(8 * scalarSize(type)); }

[[gnu::always_inline]] inline uint64_t keyFromRaw(ScalarType type, const uint8_t* p) {
  using value_detail::loadRaw;
  switch (type) {
    case ScalarType::kInt8: return loadRaw<uint8_t>(p) ^ 0x80u;
    case ScalarType::kUInt8: return loadRaw<uint8_t>(p);
    case ScalarType::kInt16: return loadRaw<uint16_t>(p) ^ 0x8000u;
    case ScalarType::kUInt16: return loadRaw<uint16_t>(p);
    case ScalarType::kInt32: return loadRaw<uint32_t>(p) ^ 0x80000000u;
    case ScalarType::kUInt32: return loadRaw<uint32_t>(p);
    case ScalarType::kInt64: return loadRaw<uint64_t>(p) ^ (uint64_t{1} << 63);
    case ScalarType::kUInt64: return loadRaw<uint64_t>(p);
    case ScalarType::kFloat32: {
      const uint32_t b = loadRaw<uint32_t>(p);
      return (b & 0x80000000u) ? uint32_t(~b) : (b | 0x80000000u);
    }
    case ScalarType::kFloat64: {
      const uint64_t b = loadRaw<uint64_t>(p);
      const uint64_t sign = uint64_t{1} << 63;
      return (b & sign) ? ~b : (b | sign);
    }
  }
  return 0;
}

[[gnu::always_inline]] inline void rawFromKey(ScalarType type, uint64_t key, uint8_t* p) {
  using value_detail::storeRaw;
  switch (type) {
    case ScalarType::kInt8: storeRaw<uint8_t>(p, static_cast<uint8_t>(key ^ 0x80u)); return;
    case ScalarType::kUInt8: storeRaw<uint8_t>(p, static_cast<uint8_t>(key)); return;
    case ScalarType::kInt16: storeRaw<uint16_t>(p, static_cast<uint16_t>(key ^ 0x8000u)); return;
    case ScalarType::kUInt16: storeRaw<uint16_t>(p, static_cast<uint16_t>(key)); return;
    case ScalarType::kInt32: storeRaw<uint32_t>(p, static_cast<uint32_t>(key ^ 0x80000000u)); return;
    case ScalarType::kUInt32: storeRaw<uint32_t>(p, static_cast<uint32_t>(key)); return;
    case ScalarType::kInt64: storeRaw<uint64_t>(p, key ^ (uint64_t{1} << 63)); return;
    case ScalarType::kUInt64: storeRaw<uint64_t>(p, key); return;
    case ScalarType::kFloat32: {
      const uint32_t k = static_cast<uint32_t>(key);
      storeRaw<uint32_t>(p, (k & 0x80000000u) ? (k & 0x7FFFFFFFu) : uint32_t(~k));
      return;
    }
    case ScalarType::kFloat64: {
      const uint64_t sign = uint64_t{1} << 63;
      storeRaw<uint64_t>(p, (key & sign) ? (key & ~sign) : ~key);
      return;
    }
  }
}

// The prediction `v` rounded to `type` (integers clamped to their range), as a key.
[[gnu::always_inline]] inline uint64_t keyFromPrediction(ScalarType type, double v) {
  using value_detail::clampRound;
  using value_detail::storeRaw;
  uint8_t raw[8];
  switch (type) {
    case ScalarType::kInt8: storeRaw<int8_t>(raw, static_cast<int8_t>(clampRound(v, -128, 127))); break;
    case ScalarType::kUInt8: storeRaw<uint8_t>(raw, static_cast<uint8_t>(clampRound(v, 0, 255))); break;
    case ScalarType::kInt16: storeRaw<int16_t>(raw, static_cast<int16_t>(clampRound(v, -32768, 32767))); break;
    case ScalarType::kUInt16: storeRaw<uint16_t>(raw, static_cast<uint16_t>(clampRound(v, 0, 65535))); break;
    case ScalarType::kInt32:
      storeRaw<int32_t>(raw, static_cast<int32_t>(clampRound(v, -2147483648.0, 2147483647.0)));
      break;
    case ScalarType::kUInt32: storeRaw<uint32_t>(raw, static_cast<uint32_t>(clampRound(v, 0, 4294967295.0))); break;
    case ScalarType::kInt64:
      // 2^63 is not an int64: stop one representable double below it.
      storeRaw<int64_t>(raw, static_cast<int64_t>(clampRound(v, -9223372036854775808.0, 9223372036854774784.0)));
      break;
    case ScalarType::kUInt64:
      storeRaw<uint64_t>(raw, static_cast<uint64_t>(clampRound(v, 0, 18446744073709549568.0)));
      break;
    case ScalarType::kFloat32: {
      float f = std::isfinite(v) && std::fabs(v) <= 3.4028234663852886e38 ? static_cast<float>(v) : 0.0f;
      storeRaw<float>(raw, f);
      break;
    }
    case ScalarType::kFloat64: storeRaw<double>(raw, std::isfinite(v) ? v : 0.0); break;
  }
  return keyFromRaw(type, raw);
}

[[gnu::always_inline]] inline double doubleFromRaw(ScalarType type, const uint8_t* p) {
  using value_detail::loadRaw;
  switch (type) {
    case ScalarType::kInt8: return loadRaw<int8_t>(p);
    case ScalarType::kUInt8: return loadRaw<uint8_t>(p);
    case ScalarType::kInt16: return loadRaw<int16_t>(p);
    case ScalarType::kUInt16: return loadRaw<uint16_t>(p);
    case ScalarType::kInt32: return loadRaw<int32_t>(p);
    case ScalarType::kUInt32: return loadRaw<uint32_t>(p);
    case ScalarType::kInt64: return static_cast<double>(loadRaw<int64_t>(p));
    case ScalarType::kUInt64: return static_cast<double>(loadRaw<uint64_t>(p));
    case ScalarType::kFloat32: return loadRaw<float>(p);
    case ScalarType::kFloat64: return loadRaw<double>(p);
  }
  return 0.0;
}

class ValueCoder {
 public:
  ValueCoder(ScalarType type, uint32_t components);

  ScalarType type() const { return type_; }
  uint32_t components() const { return components_; }

  // Codes component `comp` given the predicted key; returns the actual key (the decoder's result).
  template <class C>
  uint64_t code(C& c, uint32_t comp, uint64_t pred_key, uint64_t actual_key);

  // The shift of component `comp`: the number of low bits that every value's stored bit pattern has
  // zero, at most the width - 1; 0 until set. `exceptions`: only most values have them zero, and a bit
  // per value says which do not (those are coded at the full width in models of their own).
  void setShift(uint32_t comp, int shift, bool exceptions = false);
  int bits() const { return bits_; }
  // The number of trailing zero bits of a value's stored bit pattern (the value's type width for 0).
  static int trailingZeros(ScalarType type, const uint8_t* p);

  // The decimal places e (0..kMaxDecimals) of a float component coded in decimal form, -1 for none.
  void setDecimals(uint32_t comp, int e);
  static constexpr int kMaxDecimals = 22;  // 10^22 is the largest power of ten a double holds exactly
  // The fewest decimal places of a float value (it is n / 10^e for an integer |n| < 2^53), with that
  // n; -1 when it has none (NaN, infinity, -0.0, more places or digits than that).
  static int decimalPlaces(ScalarType type, uint64_t key, int64_t* n);

  // The value table of component `comp`: its distinct keys, ascending (the encoder's `keys`, the
  // decoder's result), of at most `limit` entries. Its values are then coded as places in the table.
  // False for a corrupt table (too long, not ascending).
  template <class C>
  bool codeTable(C& c, uint32_t comp, std::vector<uint64_t>* keys, uint64_t limit);

  // The significant digits p (1..kMaxPrintedDigits) of a float64 component coded in printed-single
  // form, 0 for none.
  void setPrinted(uint32_t comp, int digits);
  static constexpr int kMaxPrintedDigits = 17;

 private:
  static constexpr int kTreeBits = 7;   // bucket 0..64
  static constexpr int kContexts = 17;  // previous bucket / 4

  struct Component {
    std::vector<BitTree<kTreeBits>> bucket;  // [context]
    BitModel sign[65];
    BitModel high[65][4];  // the two bits below the leading one, as a 2-bit tree per bucket
    uint32_t last_bucket = 0;
    int shift = 0;
    bool exceptions = false;  // of the shift
    int decimals = -1;
    int printed = 0;
    std::vector<uint64_t> table;  // the distinct keys, ascending, of a component in table form
    int table_bits = 0;           // the width of a place in it
    BitModel not_decimal[2];      // context: the previous value's bit (decimal, printed-single or shift form)
    uint32_t last_not_decimal = 0;
  };
  // Gives a component in decimal or printed-single form its float models, after the others.
  void addEscapeModels();
  // Codes the residual of keys `w` bits wide (`mask` = 2^w - 1).
  template <class C>
  static uint64_t codeKey(C& c, Component& m, int w, uint64_t mask, uint64_t pred_key, uint64_t actual_key);

  ScalarType type_;
  uint32_t components_;
  int bits_;
  uint64_t mask_;
  std::vector<Component> comp_;  // then, once a component is decimal or printed, the float models of each one
};

// Decimal-form integers stay below 2^53 in magnitude, where every integer is exactly a double.
inline constexpr double kDecimalLimit = 9007199254740992.0;

// 10^e for e = 0..22, each exactly a double.
inline constexpr double kPowersOfTen[ValueCoder::kMaxDecimals + 1] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                                                      1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                                                      1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

// The value n / 10^e of a decimal-form component, in `type` (float32 or float64), as raw bytes.
inline void decimalValue(ScalarType type, int64_t n, int e, uint8_t* raw) {
  const double v = static_cast<double>(n) / kPowersOfTen[e];
  if (type == ScalarType::kFloat32) {
    value_detail::storeRaw<float>(raw, static_cast<float>(v));
  } else {
    value_detail::storeRaw<double>(raw, v);
  }
}

// The float64 that a float32 value f printed with p significant digits reads back as: a program that
// holds single precision values in doubles and prints them with "%.15g" writes 0.200000002980232 for
// 0.2f (Medit files from MMG do). printf's "%.*g" and strtod, exactly (std::to_chars and
// std::from_chars are exact by their definition).
inline double printedSingle(float f, int digits) {
  if (!std::isfinite(f)) return f;  // never encoded; a corrupt stream's
  char text[64];
  const auto r = std::to_chars(text, text + sizeof text, static_cast<double>(f), std::chars_format::general, digits);
  double v = 0;
  std::from_chars(text, r.ptr, v);
  return v;
}

// The float32 whose printing with `digits` digits is the float64 value with key `key`, as a key, or
// false.
inline bool printedSingleKey(uint64_t key, int digits, uint64_t* out) {
  uint8_t raw[8];
  rawFromKey(ScalarType::kFloat64, key, raw);
  const double v = value_detail::loadRaw<double>(raw);
  if (!(std::fabs(v) <= 3.4028234663852886e38)) return false;  // also NaN
  const float f = static_cast<float>(v);
  const double back = printedSingle(f, digits);
  if (std::memcmp(&back, &v, sizeof v) != 0) return false;
  uint8_t fraw[4];
  value_detail::storeRaw<float>(fraw, f);
  *out = keyFromRaw(ScalarType::kFloat32, fraw);
  return true;
}

// The significant digits of the shortest decimal that reads back as the float64 value with key `key`
// (0 for infinities and NaN).
inline int shortestDigits(uint64_t key) {
  uint8_t raw[8];
  rawFromKey(ScalarType::kFloat64, key, raw);
  char text[64];
  const auto r =
      std::to_chars(text, text + sizeof text, value_detail::loadRaw<double>(raw), std::chars_format::scientific);
  int digits = 0;
  for (const char* c = text; c < r.ptr && *c != 'e'; ++c) digits += *c >= '0' && *c <= '9';
  return digits;
}

// The integer n whose decimal value n / 10^e is the value with key `key`, or false.
inline bool decimalInteger(ScalarType type, uint64_t key, int e, int64_t* out) {
  uint8_t raw[8], back[8];
  rawFromKey(type, key, raw);
  const double v = doubleFromRaw(type, raw);
  const double scaled = v * kPowersOfTen[e];
  if (!(std::fabs(scaled) < kDecimalLimit)) return false;  // also NaN
  const int64_t n0 = static_cast<int64_t>(std::nearbyint(scaled));
  const size_t size = scalarSize(type);
  for (const int64_t n : {n0, n0 - 1, n0 + 1}) {  // the product may have rounded across a half
    decimalValue(type, n, e, back);
    if (std::memcmp(raw, back, size) == 0) {
      *out = n;
      return true;
    }
  }
  return false;
}

template <class C>
bool ValueCoder::codeTable(C& c, uint32_t comp, std::vector<uint64_t>* keys, uint64_t limit) {
  const uint32_t last = C::kEncoding ? static_cast<uint32_t>(keys->size() - 1) : 0;  // D - 1 (the decoder's is read)
  const uint32_t length = c.direct(static_cast<uint32_t>(bitLength(last)), 6);
  if (length > 32) return false;
  const uint64_t size = uint64_t{c.direct(last, static_cast<int>(length))} + 1;
  if (size > limit) return false;
  // Keys ascend, mostly by steps like the one before (a lattice's coordinates): each is predicted
  // by the step before it, in models of the table's own. The decoder's table grows with what it
  // decodes, not with the size a corrupt stream may claim.
  Component models;
  models.bucket.resize(kContexts);
  std::vector<uint64_t>& k = *keys;
  for (size_t i = 0; i < size; ++i) {
    const uint64_t pred = i == 0 ? 0 : (i == 1 ? k[0] + 1 : 2 * k[i - 1] - k[i - 2]) & mask_;
    const uint64_t key = codeKey(c, models, bits_, mask_, pred, C::kEncoding ? k[i] : 0);
    if constexpr (!C::kEncoding) {
      if ((i > 0 && key <= k[i - 1]) || !c.ok()) return false;
      k.push_back(key);
    }
  }
  Component& m = comp_[comp];
  m.table = std::move(*keys);
  m.table_bits = std::max(1, bitLength(size - 1));
  return true;
}

template <class C>
uint64_t ValueCoder::code(C& c, uint32_t comp, uint64_t pred_key, uint64_t actual_key) {
  Component& m = comp_[comp];
  if (!m.table.empty()) {
    // The value's place, against the place of the table's key nearest to the prediction (the lower
    // of two as near).
    const std::vector<uint64_t>& t = m.table;
    size_t at = static_cast<size_t>(std::lower_bound(t.begin(), t.end(), pred_key) - t.begin());
    if (at == t.size() || (at > 0 && pred_key - t[at - 1] <= t[at] - pred_key)) --at;
    uint64_t place = 0;
    if constexpr (C::kEncoding)
      place = static_cast<uint64_t>(std::lower_bound(t.begin(), t.end(), actual_key) - t.begin());
    const int w = m.table_bits;
    place = codeKey(c, m, w, (uint64_t{1} << w) - 1, at, place);
    if (place >= t.size()) {
      c.markCorrupt();
      place = t.size() - 1;
    }
    return t[place];
  }
  if (m.printed > 0) {
    uint64_t single = 0;
    uint32_t other = 0;
    if constexpr (C::kEncoding) other = !printedSingleKey(actual_key, m.printed, &single);
    other = c.bit(m.not_decimal[m.last_not_decimal], other);
    m.last_not_decimal = other;
    if (other) return codeKey(c, comp_[components_ + comp], bits_, mask_, pred_key, actual_key);
    // The float32 keys: the prediction rounded to float32, the value's float32.
    uint8_t raw[8];
    rawFromKey(type_, pred_key, raw);
    const uint64_t k =
        codeKey(c, m, 32, 0xFFFFFFFFu, keyFromPrediction(ScalarType::kFloat32, doubleFromRaw(type_, raw)), single);
    rawFromKey(ScalarType::kFloat32, k, raw);
    value_detail::storeRaw<double>(raw, printedSingle(value_detail::loadRaw<float>(raw), m.printed));
    return keyFromRaw(type_, raw);
  }
  if (m.decimals >= 0) {
    int64_t n = 0;
    uint32_t other = 0;
    if constexpr (C::kEncoding) other = !decimalInteger(type_, actual_key, m.decimals, &n);
    other = c.bit(m.not_decimal[m.last_not_decimal], other);
    m.last_not_decimal = other;
    if (other) return codeKey(c, comp_[components_ + comp], bits_, mask_, pred_key, actual_key);
    // The integers as int64 keys: the prediction's decimal form rounded, the value's exact.
    const uint64_t sign = uint64_t{1} << 63;
    uint8_t raw[8];
    rawFromKey(type_, pred_key, raw);
    const double np =
        value_detail::clampRound(doubleFromRaw(type_, raw) * kPowersOfTen[m.decimals], -kDecimalLimit, kDecimalLimit);
    const uint64_t k = codeKey(c, m, 64, ~uint64_t{0}, static_cast<uint64_t>(static_cast<int64_t>(np)) ^ sign,
                               static_cast<uint64_t>(n) ^ sign);
    decimalValue(type_, static_cast<int64_t>(k ^ sign), m.decimals, raw);
    return keyFromRaw(type_, raw);
  }
  const int z = m.shift;
  if (z == 0) return codeKey(c, m, bits_, mask_, pred_key, actual_key);
  if (m.exceptions) {
    uint32_t other = 0;
    if constexpr (C::kEncoding) {
      uint8_t raw[8];
      rawFromKey(type_, actual_key, raw);
      other = trailingZeros(type_, raw) < z;
    }
    other = c.bit(m.not_decimal[m.last_not_decimal], other);
    m.last_not_decimal = other;
    if (other) return codeKey(c, comp_[components_ + comp], bits_, mask_, pred_key, actual_key);
  }
  // The low z bits of every value's pattern are zero: those of a positive float's key and of an
  // integer's too, those of a negative float's key one (its key inverts the pattern).
  const int w = bits_ - z;
  const uint64_t key = codeKey(c, m, w, (uint64_t{1} << w) - 1, pred_key >> z, actual_key >> z);
  const bool ones = isFloatType(type_) && ((key >> (w - 1)) & 1) == 0;
  return (key << z) | (ones ? (uint64_t{1} << z) - 1 : 0);
}

template <class C>
uint64_t ValueCoder::codeKey(C& c, Component& m, int w, uint64_t mask, uint64_t pred_key, uint64_t actual_key) {
  const uint64_t r = (actual_key - pred_key) & mask;
  const uint64_t half = uint64_t{1} << (w - 1);
  const bool negative = r >= half && r != 0;
  uint64_t mag = negative ? ((~r + 1) & mask) : r;
  if (negative && mag == 0) mag = half;  // unreachable for widths < 64; keeps -2^63 exact
  uint32_t k = 0;
  if (mag) k = 64 - static_cast<uint32_t>(__builtin_clzll(mag));
  k = m.bucket[m.last_bucket >> 2].code(c, k);
  if (k > static_cast<uint32_t>(w)) k = w;  // corrupt stream; the decoder fails later
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
  const uint64_t res = s ? ((~out + 1) & mask) : out;
  return (pred_key + res) & mask;
}

}  // namespace gtn
