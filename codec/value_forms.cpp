// The encoder's choice of a component's value form (codec/value_forms.h): each form is costed on the
// same sample of pairs of consecutive values, and the cheapest that saves a twentieth is kept.
#include "codec/value_forms.h"

#include <cmath>
#include <utility>

namespace gtn::level {

namespace {

// Two consecutive values of the source, as each form would see them.
struct Pair {
  int places[2];
  double integer[2];
  float float_bits;  // bit length of the difference of the shifted keys
  uint64_t keys[2];
  int zeros[2];  // trailing zero bits of the stored patterns, at most the width - 1
};

// The pairs the forms are costed on: every consecutive pair, or 256 pseudo-random ones (a regular
// stride can alias with a grid's layout) for more than 1024 values. `z`: the shift every value
// allows. [*lo, *hi]: the range of decimal places the values have (lo > hi if none has any).
std::vector<Pair> samplePairs(ScalarType type, const uint8_t* p, size_t n, size_t stride, int z, int* lo, int* hi) {
  struct Value {
    uint64_t key;
    int places;
    double integer;
    int zeros;
  };
  *lo = ValueCoder::kMaxDecimals + 1, *hi = -1;
  auto valueAt = [&](size_t i) {
    Value v{keyFromRaw(type, p + i * stride), -1, 0,
            std::min(ValueCoder::trailingZeros(type, p + i * stride), scalarBits(type) - 1)};
    int64_t integer = 0;
    v.places = ValueCoder::decimalPlaces(type, v.key, &integer);
    v.integer = static_cast<double>(integer);
    if (v.places >= 0) *lo = std::min(*lo, v.places), *hi = std::max(*hi, v.places);
    return v;
  };
  std::vector<Pair> pairs;
  const bool sample = n > 1024;
  uint64_t state = 0x9E3779B97F4A7C15u;
  // Consecutive pairs share a value: its decimal places (a shortest-decimal conversion, most of
  // the cost) are found once.
  Value next = sample ? Value{} : valueAt(0);
  for (size_t k = 0; k < (sample ? 256 : n - 1); ++k) {
    state ^= state << 13, state ^= state >> 7, state ^= state << 17;
    const size_t i = sample ? state % (n - 1) : k;
    const Value a = sample ? valueAt(i) : next, b = valueAt(i + 1);
    next = b;
    Pair pair{{a.places, b.places}, {a.integer, b.integer}, 0, {a.key, b.key}, {a.zeros, b.zeros}};
    const uint64_t d = (b.key > a.key ? b.key - a.key : a.key - b.key) >> z;
    pair.float_bits = static_cast<float>(bitLength(d));
    pairs.push_back(pair);
  }
  return pairs;
}

// Decimal form with e places, lo <= e <= hi: a pair costs the bit length of its integers'
// difference, or a float and a flag where either value has no such form.
void tryDecimals(const std::vector<Pair>& pairs, int lo, int hi, double* best, ValueForm* form) {
  for (int e = lo; e <= hi; ++e) {
    double cost = 0;
    for (const Pair& pair : pairs) {
      double at_e[2];
      for (int j = 0; j < 2; ++j)
        at_e[j] =
            pair.places[j] >= 0 && pair.places[j] <= e ? pair.integer[j] * kPowersOfTen[e - pair.places[j]] : 1e300;
      const bool both = std::fabs(at_e[0]) < kDecimalLimit && std::fabs(at_e[1]) < kDecimalLimit;
      cost += both ? std::log2(std::fabs(at_e[1] - at_e[0]) + 1) + 1 : pair.float_bits + 4;
    }
    if (cost < *best) *best = cost, *form = {e, 0, 0};
  }
}

// Float64 values that are float32 values printed with p digits (0.200000002980232 for 0.2f): the
// p that most of the pairs' first values have, costed like the decimal places, on the float32 keys.
void tryPrintedSingle(const std::vector<Pair>& pairs, double* best, ValueForm* form) {
  int count[ValueCoder::kMaxPrintedDigits] = {};
  uint64_t single = 0;
  // A printing with p digits reads back as v only if v's shortest decimal has at most p: a full
  // double (17) is never tried, so this costs one conversion per value where no form applies.
  for (const Pair& pair : pairs)
    for (int digits = std::max(1, shortestDigits(pair.keys[0])); digits < ValueCoder::kMaxPrintedDigits; ++digits)
      count[digits] += printedSingleKey(pair.keys[0], digits, &single);
  int digits = 0;
  for (int d = 1; d < ValueCoder::kMaxPrintedDigits; ++d)
    if (count[d] > count[digits]) digits = d;
  if (digits == 0) return;
  double cost = 0;
  for (const Pair& pair : pairs) {
    uint64_t k32[2];
    const bool both =
        printedSingleKey(pair.keys[0], digits, &k32[0]) && printedSingleKey(pair.keys[1], digits, &k32[1]);
    cost += both ? bitLength(k32[1] > k32[0] ? k32[1] - k32[0] : k32[0] - k32[1]) + 1 : pair.float_bits + 4;
  }
  if (cost < *best) *best = cost, *form = {-1, digits, 0};
}

// A shift with exceptions: s low bits that most values have zero, but not all (sums of float32
// values kept in doubles, with a few full doubles; exact zeros among computed values). Each s above
// `z` that some sampled value has is costed like the decimal places, on the keys shifted by s; a
// pair's second value is costed as predicted by the first, whose low bits the shift drops whatever
// they are (a zero next to full doubles costs a few bits of exponent instead of a whole double). The
// escape's models start cold: a few dozen bits.
void tryShiftWithExceptions(const std::vector<Pair>& pairs, int z, double* best, ValueForm* form) {
  constexpr double kColdModels = 32;
  bool tried[64] = {};
  for (const Pair& candidate : pairs) {
    for (const int sh : candidate.zeros) {
      if (sh <= z || tried[sh]) continue;
      tried[sh] = true;
      double cost = kColdModels;
      for (const Pair& pair : pairs) {
        const uint64_t d = pair.keys[1] > pair.keys[0] ? pair.keys[1] - pair.keys[0] : pair.keys[0] - pair.keys[1];
        cost += pair.zeros[1] >= sh ? bitLength(d >> sh) + 1 : pair.float_bits + 4;
      }
      if (cost < *best) *best = cost, *form = {-1, 0, static_cast<uint32_t>(sh), true};
    }
  }
}

// A value table: few distinct values (a lattice's coordinates, a field with a few levels) cost
// their places in the table, plus the table. Only when the sampled values repeat (at most half of
// them distinct) are all the values sorted, and the table is kept to a quarter of them.
void tryTable(ScalarType type, const uint8_t* p, size_t n, size_t stride, const std::vector<Pair>& pairs, double best,
              ValueForm* form) {
  std::vector<uint64_t> keys;
  for (const Pair& pair : pairs) keys.insert(keys.end(), pair.keys, pair.keys + 2);
  std::sort(keys.begin(), keys.end());
  const size_t sampled_distinct = static_cast<size_t>(std::unique(keys.begin(), keys.end()) - keys.begin());
  if (sampled_distinct > pairs.size()) return;  // more than half of the 2 per pair
  keys.resize(n);
  for (size_t i = 0; i < n; ++i) keys[i] = keyFromRaw(type, p + i * stride);
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  if (keys.size() * 4 > n) return;
  double table_bits = 12;
  for (size_t i = 1; i < keys.size(); ++i) {
    const uint64_t pred = i == 1 ? keys[0] + 1 : 2 * keys[i - 1] - keys[i - 2];
    const int64_t r = static_cast<int64_t>(keys[i] - pred);
    table_bits += bitLength(static_cast<uint64_t>(r < 0 ? -r : r)) + 2;
  }
  double cost = table_bits * static_cast<double>(pairs.size()) / static_cast<double>(n - 1);
  for (const Pair& pair : pairs) {
    const auto a = std::lower_bound(keys.begin(), keys.end(), pair.keys[0]),
               b = std::lower_bound(keys.begin(), keys.end(), pair.keys[1]);
    cost += bitLength(static_cast<uint64_t>(a < b ? b - a : a - b)) + 1;
  }
  if (cost < best) *form = {-1, 0, 0, false, std::move(keys)};
}

}  // namespace

ValueForm chooseValueForm(ScalarType type, const uint8_t* p, size_t n, size_t stride) {
  ValueForm form;
  int z = scalarBits(type) - 1;
  for (size_t i = 0; i < n && z > 0; ++i) z = std::min(z, ValueCoder::trailingZeros(type, p + i * stride));
  form.shift = static_cast<uint32_t>(z);
  if (n < 2) return form;
  int lo = 0, hi = 0;
  const std::vector<Pair> pairs = samplePairs(type, p, n, stride, z, &lo, &hi);
  // The plain form's cost, less the twentieth another form must save.
  double floats = 0;
  for (const Pair& pair : pairs) floats += pair.float_bits + 1;
  double best = 0.95 * floats;
  tryDecimals(pairs, lo, hi, &best, &form);
  // Values that are float32 values exactly have a shift of 29 or more instead.
  if (type == ScalarType::kFloat64 && form.shift < 29) tryPrintedSingle(pairs, &best, &form);
  // No gain below some 64 values: the exceptions' models start cold.
  if (n < 64) return form;
  tryShiftWithExceptions(pairs, z, &best, &form);
  // The estimate takes neighbours in the source's order for predictions, which misses by more than
  // the table's own bits on small lattices (an MMG cube of 152 points would grow by a tenth): the
  // table is weighed only from 1024 values on.
  if (n < 1024) return form;
  tryTable(type, p, n, stride, pairs, best, &form);
  return form;
}

}  // namespace gtn::level
