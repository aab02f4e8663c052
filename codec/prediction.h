// Prediction in the level codec (spec section 10.5): the rules that predict a new vertex's
// coordinates and field values from its stencil (the gate face (a, b, c) and the vertex d behind it),
// the coordinate error carries, the apex prediction, and the encoder's cost estimates with which it
// picks a rule. Everything here is a pure function of its arguments: the coder's state (positions,
// values, models) stays with the parts that own it.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "codec/range_coder.h"
#include "codec/value_coder.h"
#include "mesh/index.h"

namespace gtn::level {

// How the field values of a new vertex are predicted.
struct FieldPrediction {
  // kEdge: a point on the edge (s[0], s[1]), predicted at its midpoint (section 10.5).
  enum Kind { kLast, kParallelogram, kInterpolate, kAverage, kEdge } kind = kLast;
  uint32_t s[4] = {kNoIndex, kNoIndex, kNoIndex, kNoIndex};
};

constexpr double kPredictK = 0.6;  // new vertex at g + k (g - d) (spec section 10.5)

constexpr double kMaxKey = 1.7976931348623157e308;  // candidate distances beyond this (inf, NaN) tie here

// Prediction rules for a vertex x behind the front face (a, b, c) whose decoded tetrahedron has
// fourth vertex d: weights of (a, b, c, d). Rule 0 is the default (coordinates: g + k (g - d);
// fields: the interpolant of (a, b, c, d) at x). Rules 1-8 are the parallelograms a structured
// grid makes exact, and two reflections; rules 9-12 repeat one stencil vertex, which is exact where a
// grid copies its boundary values to the next layer (blunt fin repeats two planes this way) and for
// coincident points.
constexpr uint32_t kRules = 13;
constexpr uint32_t kCoordRules = 9;  // coordinates have their own per-axis copies (spec section 10.5)
// Field rules 13-15 repeat the first three apex candidates (spec section 10.4's order).
constexpr uint32_t kFieldRules = 16;
constexpr uint32_t kCandidateRules = 3;
// Coordinate error carries (spec section 10.5): none, the stencil's a, b, c, d, the first three apex
// candidates.
constexpr uint32_t kCarries = 8;
// What a carry must save beyond its signalling for the encoder to choose it, in 1/16 bits: the
// residual-length estimate is coarse, and the smallest of 8 x 9 estimates is biased low (on meshes
// without grid structure a carry wins by chance; 3 bits keeps those files within 0.3%).
constexpr int kCarryMargin = 48;
constexpr double kRuleWeights[kRules][4] = {
    {0, 0, 0, 0},  {1, 1, 0, -1}, {0, 1, 1, -1},
    {1, 0, 1, -1}, {1, 1, -1, 0}, {-1, 1, 1, 0},
    {1, -1, 1, 0}, {1, 1, 1, -2}, {2.0 / 3, 2.0 / 3, 2.0 / 3, -1},
    {1, 0, 0, 0},  {0, 1, 0, 0},  {0, 0, 1, 0},
    {0, 0, 0, 1},
};

// The prediction of rule r (r < kRules) from the stencil values x = (a, b, c, d): the sum of
// kRuleWeights[r][j] * x[j] over the non-zero weights, in order, starting from +0 (spec section 10.5).
// The weights are compile-time constants, as the encoder tries every rule at every vertex; a stencil
// value whose weight is zero is never read.
template <uint32_t r>
inline double weightedRule(const double x[4]) {
  double v = 0;
  if constexpr (kRuleWeights[r][0] != 0.0) v += kRuleWeights[r][0] * x[0];
  if constexpr (kRuleWeights[r][1] != 0.0) v += kRuleWeights[r][1] * x[1];
  if constexpr (kRuleWeights[r][2] != 0.0) v += kRuleWeights[r][2] * x[2];
  if constexpr (kRuleWeights[r][3] != 0.0) v += kRuleWeights[r][3] * x[3];
  return v;
}
template <uint32_t... r>
constexpr std::array<double (*)(const double*), sizeof...(r)> weightedRuleTable(std::integer_sequence<uint32_t, r...>) {
  return {&weightedRule<r>...};
}
constexpr auto kWeightedRule = weightedRuleTable(std::make_integer_sequence<uint32_t, kRules>());
// Every rule's prediction at once, out[r] = weightedRule<r>(x) (out[0] = 0): straight-line code for
// the encoder, which tries them all.
template <uint32_t... r>
inline void weightedRules(const double x[4], double* out, std::integer_sequence<uint32_t, r...>) {
  ((out[r] = weightedRule<r>(x)), ...);
}

// Whether rule `rule` is one of the first `rules` and its stencil is there (d only with has_d).
inline bool ruleAllowed(uint32_t rule, bool has_d, uint32_t rules) {
  return rule < rules && (has_d || kRuleWeights[rule][3] == 0.0);
}

// The i-th prediction rule the encoder tries when `last` was chosen before: `last` first (most
// others then stop early), then the rest in order.
inline uint32_t triedRule(uint32_t i, uint32_t last) { return i == 0 ? last : (i <= last ? i - 1 : i); }

// std::floor(y) for y < 1e18 without a library call (baseline x86-64 has no rounding instruction):
// from -2^52 up every value converts to int64 exactly or truncates toward zero; below, every double
// is an integer already. floor(-0.0) comes out +0.0, which compares equal: the order is the same.
inline double floorKey(double y) {
  if (!(y > -4503599627370496.0)) return y;
  const double d = static_cast<double>(static_cast<int64_t>(y));
  return d > y ? d - 1 : d;
}

// Squared distance from q to a predicted position p (apex or parallelogram), a NaN or overflow
// counting as the largest finite double (sections 10.3 and 10.4).
inline double apexDistance(const double* q, const double p[3]) {
  const double dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
  const double d = dx * dx + dy * dy + dz * dz;
  return d <= kMaxKey ? d : kMaxKey;
}

// A source coordinate (held as double) stored as the file's coordinate type (float32 or float64).
inline void storeCoordinate(ScalarType ct, double v, uint8_t* raw) {
  if (ct == ScalarType::kFloat32) {
    const float f = static_cast<float>(v);
    std::memcpy(raw, &f, 4);
  } else {
    std::memcpy(raw, &v, 8);
  }
}

// What coding each symbol through `tree` costs now, in 1/16 bits (the encoder weighs a prediction
// rule's signalling against the residual bits it saves). One walk over the nodes prices every
// symbol, as the encoder tries them all: a symbol's cost is the sum along its path from the root.
template <int kBits>
struct SymbolCosts {
  int path[2 << kBits];  // cost of reaching each node; the leaves are the symbols
  int operator[](uint32_t symbol) const { return path[(1 << kBits) + symbol]; }
};
template <int kBits>
SymbolCosts<kBits> symbolCosts(const BitTree<kBits>& tree) {
  static const std::array<uint16_t, 4096> kCost = [] {
    std::array<uint16_t, 4096> t{};
    for (size_t i = 0; i < t.size(); ++i)
      t[i] = static_cast<uint16_t>(std::lround(-16.0 * std::log2((i + 0.5) / 4096.0)));
    return t;
  }();
  SymbolCosts<kBits> c;
  c.path[1] = 0;
  for (uint32_t node = 1; node < (1u << kBits); ++node) {
    const uint32_t p0 = tree.m[node].p0();
    c.path[2 * node] = c.path[node] + kCost[p0 >> 4];
    c.path[2 * node + 1] = c.path[node] + kCost[(65536 - p0) >> 4];
  }
  return c;
}

// The keys of a `bits`-wide type are its low `bits` bits.
inline uint64_t keyMask(int bits) { return bits == 64 ? ~uint64_t{0} : ((uint64_t{1} << bits) - 1); }
// Magnitude class of the residual between two keys (`mask`: their type's keyMask), the encoder's cost.
inline int residualBits(uint64_t actual, uint64_t pred, uint64_t mask) {
  const uint64_t r = (actual - pred) & mask, n = (~r + 1) & mask;
  return bitLength(r < n ? r : n);
}
// Adds to cost[r] the residual cost of prediction v[r], 16 * residualBits, for r < kCount (a multiple
// of 4): the rules of one component whose actual key is `actual`.
template <uint32_t kCount, class Type>
inline void addRuleCosts(Type type, uint64_t actual, const double* v, int* cost) {
  static_assert(kCount % 4 == 0);
#if defined(__SSE2__)
  // Four rules at a time for float32, the usual field type: the same arithmetic as
  // keyFromPrediction (the range check, the float conversion) and residualBits (the smaller of the
  // residual and its negation, modulo 2^32), whose bit length is the exponent of its exact
  // conversion to double.
  if constexpr (std::is_same_v<Type, std::integral_constant<ScalarType, ScalarType::kFloat32>>) {
    const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7FFFFFFFFFFFFFFF));
    const __m128d max_float = _mm_set1_pd(3.4028234663852886e38);
    const __m128i sign = _mm_set1_epi32(static_cast<int>(0x80000000u));
    const __m128i act = _mm_set1_epi32(static_cast<int>(actual));
    for (uint32_t r = 0; r < kCount; r += 4) {
      __m128 f[2];
      for (int h = 0; h < 2; ++h) {
        const __m128d d = _mm_loadu_pd(v + r + 2 * h);
        const __m128d in_range = _mm_cmple_pd(_mm_and_pd(d, abs_mask), max_float);  // not NaN or infinite
        f[h] = _mm_cvtpd_ps(_mm_and_pd(d, in_range));
      }
      const __m128i bits = _mm_castps_si128(_mm_movelh_ps(f[0], f[1]));
      const __m128i key = _mm_xor_si128(bits, _mm_or_si128(_mm_srai_epi32(bits, 31), sign));
      const __m128i res = _mm_sub_epi32(act, key), neg = _mm_sub_epi32(_mm_setzero_si128(), res);
      const __m128i less = _mm_cmplt_epi32(_mm_xor_si128(res, sign), _mm_xor_si128(neg, sign));
      const __m128i mag = _mm_or_si128(_mm_and_si128(less, res), _mm_andnot_si128(less, neg));
      // As int32 the largest magnitude, 2^31, is -2^31: the exponent is the same.
      auto lengths = [&](__m128i two) {
        const __m128i e =
            _mm_and_si128(_mm_srli_epi64(_mm_castpd_si128(_mm_cvtepi32_pd(two)), 52), _mm_set1_epi64x(0x7FF));
        return _mm_subs_epu16(e, _mm_set1_epi16(1022));  // 0 (exponent 0) stays 0
      };
      const __m128i lo = lengths(mag), hi = lengths(_mm_shuffle_epi32(mag, _MM_SHUFFLE(3, 2, 3, 2)));
      const __m128i len =
          _mm_castps_si128(_mm_shuffle_ps(_mm_castsi128_ps(lo), _mm_castsi128_ps(hi), _MM_SHUFFLE(2, 0, 2, 0)));
      __m128i* c = reinterpret_cast<__m128i*>(cost + r);
      _mm_storeu_si128(c, _mm_add_epi32(_mm_loadu_si128(c), _mm_slli_epi32(len, 4)));
    }
    return;
  }
#endif
  const uint64_t mask = keyMask(scalarBits(type));
  for (uint32_t r = 0; r < kCount; ++r) cost[r] += 16 * residualBits(actual, keyFromPrediction(type, v[r]), mask);
}

// The weights of the stencil vertices (a, b, c, d) = s[0..3] with which a field value is predicted
// at x for prediction `kind`, and how many of them count: kInterpolate the barycentric coordinates
// of x in (a, b, c, d), falling back to kAverage when the tetrahedron is flat or x lies far outside
// it (a weight beyond 8); kAverage a third each of a, b and c; kParallelogram a + b - c; kEdge the
// midpoint of (a, b). kLast weighs nothing (0: the previous vertex's values are the prediction).
// s[j] may be null where the kind does not read it.
inline int stencilWeights(FieldPrediction::Kind kind, const double* const s[4], const double* x, double lambda[4]) {
  lambda[0] = 1, lambda[1] = lambda[2] = lambda[3] = 0;
  int n = 1;
  if (kind == FieldPrediction::kLast) return 0;
  if (kind == FieldPrediction::kInterpolate) {
    const double *a = s[0], *b = s[1], *c = s[2], *d = s[3];
    double e1[3], e2[3], e3[3], r[3];
    for (int i = 0; i < 3; ++i) {
      e1[i] = b[i] - a[i];
      e2[i] = c[i] - a[i];
      e3[i] = d[i] - a[i];
      r[i] = x[i] - a[i];
    }
    auto det = [](const double* u, const double* v, const double* w) {
      return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
             u[2] * (v[0] * w[1] - v[1] * w[0]);
    };
    const double vol = det(e1, e2, e3);
    bool ok = vol != 0.0 && std::isfinite(vol);
    if (ok) {
      lambda[1] = det(r, e2, e3) / vol;
      lambda[2] = det(e1, r, e3) / vol;
      lambda[3] = det(e1, e2, r) / vol;
      lambda[0] = 1.0 - lambda[1] - lambda[2] - lambda[3];
      for (int j = 0; j < 4; ++j)
        if (!(std::fabs(lambda[j]) <= 8.0)) ok = false;
    }
    if (ok) return 4;
    kind = FieldPrediction::kAverage;
  }
  if (kind == FieldPrediction::kAverage) {
    lambda[0] = lambda[1] = lambda[2] = 1.0 / 3.0;
    n = 3;
  } else if (kind == FieldPrediction::kParallelogram) {
    lambda[0] = 1;
    lambda[1] = 1;
    lambda[2] = -1;
    n = 3;
  } else if (kind == FieldPrediction::kEdge) {
    lambda[0] = lambda[1] = 0.5;
    n = 2;
  }
  return n;
}

// The predicted apex behind the front face (a, b, c) (spec section 10.5): g + k (g - d) from the
// face's centroid g when the vertex d of the tetrahedron before it is known, else (behind a boundary
// face, d null) g moved along the face normal (b - a) x (c - a) by 0.8 of the mean edge length.
inline void predictApex(const double* a, const double* b, const double* c, const double* d, double p[3]) {
  double gc[3];
  for (int i = 0; i < 3; ++i) gc[i] = (a[i] + b[i] + c[i]) / 3.0;
  if (d) {
    for (int i = 0; i < 3; ++i) p[i] = gc[i] + kPredictK * (gc[i] - d[i]);
    return;
  }
  double e1[3], e2[3];
  for (int i = 0; i < 3; ++i) {
    e1[i] = b[i] - a[i];
    e2[i] = c[i] - a[i];
  }
  const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
  const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  auto len = [](const double* u, const double* v) {
    return std::sqrt((u[0] - v[0]) * (u[0] - v[0]) + (u[1] - v[1]) * (u[1] - v[1]) + (u[2] - v[2]) * (u[2] - v[2]));
  };
  const double edge = (len(a, b) + len(b, c) + len(c, a)) / 3.0;
  const double scale = nl > 0 && std::isfinite(nl) ? 0.8 * edge / nl : 0.0;
  for (int i = 0; i < 3; ++i) p[i] = gc[i] + n[i] * scale;
}

}  // namespace gtn::level
