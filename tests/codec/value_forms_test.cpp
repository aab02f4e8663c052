// The value forms of spec section 10.2: chooseValueForm picks the form the data has (decimal places,
// printed-single digits, a shift, a table), and every chosen form, declared through codeValueForm
// and read back, codes the values losslessly.
#include "codec/value_forms.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace gtn::level {
namespace {

struct Random {
  uint64_t s = 0x2545F4914F6CDD1Du;
  uint64_t next() {
    s ^= s >> 12, s ^= s << 25, s ^= s >> 27;
    return s * 0x2545F4914F6CDD1Du;
  }
  int below(int n) { return static_cast<int>(next() % static_cast<uint64_t>(n)); }
};

template <class T>
std::vector<uint8_t> bytesOf(const std::vector<T>& v) {
  std::vector<uint8_t> out(v.size() * sizeof(T));
  std::memcpy(out.data(), v.data(), out.size());
  return out;
}

// A random walk of n values with two decimal places, as a text format stores them.
std::vector<double> decimals2(size_t n) {
  Random r;
  std::vector<double> v(n);
  long cents = 123456;
  for (double& x : v) {
    cents += r.below(41) - 20;
    x = static_cast<double>(cents) / 100.0;
  }
  return v;
}

// Float32 values of a random walk printed with 15 significant digits and read back as float64.
std::vector<double> printedSingles(size_t n) {
  Random r;
  std::vector<double> v(n);
  float f = 0.7f;
  for (double& x : v) {
    f += static_cast<float>(r.below(2001) - 1000) * 1e-4f;
    char text[64];
    std::snprintf(text, sizeof text, "%.15g", static_cast<double>(f));
    x = std::strtod(text, nullptr);
  }
  return v;
}

// Writes `form` for component 0 of `type`, reads it back, then codes `values` (predicted by the
// previous value) with each side's ValueCoder: returns the decoded values' bytes, or the decoder's
// complaint about the declaration.
std::string roundTrip(ScalarType type, const std::vector<uint8_t>& raw, const ValueForm& form,
                      std::vector<uint8_t>* out) {
  const size_t vs = scalarSize(type), n = raw.size() / vs;
  std::vector<uint8_t> stream;
  {
    EntropyCoder<true> c(&stream);
    ValueFormModels models;
    ValueCoder vc(type, 1);
    EXPECT_EQ(codeValueForm(c, models, vc, type, 0, form, n), "");
    uint64_t prev = keyFromPrediction(type, 0.0);
    for (size_t i = 0; i < n; ++i) prev = vc.code(c, 0, prev, keyFromRaw(type, &raw[i * vs]));
    c.finish();
  }
  EntropyCoder<false> c(stream);
  ValueFormModels models;
  ValueCoder vc(type, 1);
  const std::string error = codeValueForm(c, models, vc, type, 0, ValueForm{}, n);
  if (!error.empty()) return error;
  out->assign(raw.size(), 0);
  uint64_t prev = keyFromPrediction(type, 0.0);
  for (size_t i = 0; i < n; ++i) {
    prev = vc.code(c, 0, prev, 0);
    rawFromKey(type, prev, &(*out)[i * vs]);
  }
  EXPECT_TRUE(c.finishedCleanly());
  return "";
}

void expectRoundTrip(ScalarType type, const std::vector<uint8_t>& raw, const ValueForm& form) {
  std::vector<uint8_t> back;
  ASSERT_EQ(roundTrip(type, raw, form, &back), "");
  EXPECT_EQ(back, raw);
}

TEST(ChooseValueForm, TwoDecimalPlacesTakeTheDecimalForm) {
  for (size_t n : {200u, 5000u}) {  // every pair, and a sample of pairs
    const std::vector<uint8_t> raw = bytesOf(decimals2(n));
    const ValueForm form = chooseValueForm(ScalarType::kFloat64, raw.data(), n, 8);
    EXPECT_EQ(form.decimals, 2) << n;
    EXPECT_EQ(form.printed, 0);
    EXPECT_TRUE(form.table.empty());
    expectRoundTrip(ScalarType::kFloat64, raw, form);
  }
}

TEST(ChooseValueForm, PrintedSinglesTakeThePrintedSingleForm) {
  const size_t n = 3000;
  const std::vector<uint8_t> raw = bytesOf(printedSingles(n));
  const ValueForm form = chooseValueForm(ScalarType::kFloat64, raw.data(), n, 8);
  EXPECT_EQ(form.printed, 15);
  EXPECT_EQ(form.decimals, -1);
  expectRoundTrip(ScalarType::kFloat64, raw, form);
}

TEST(ChooseValueForm, Float32ValuesInDoublesShiftOutTheirLowBits) {
  Random r;
  std::vector<double> v(500);
  for (double& x : v) x = static_cast<double>(static_cast<float>(r.below(1 << 20)) * 0.37f);
  const std::vector<uint8_t> raw = bytesOf(v);
  const ValueForm form = chooseValueForm(ScalarType::kFloat64, raw.data(), v.size(), 8);
  EXPECT_GE(form.shift, 29u);
  EXPECT_EQ(form.printed, 0);
  EXPECT_FALSE(form.exceptions);
  expectRoundTrip(ScalarType::kFloat64, raw, form);
}

TEST(ChooseValueForm, MultiplesOfEightShiftByThree) {
  Random r;
  std::vector<int32_t> v(300);
  for (int32_t& x : v) x = 8 * (r.below(100000) - 50000);
  v[17] = 24;  // the smallest number of trailing zeros decides: 3
  const std::vector<uint8_t> raw = bytesOf(v);
  const ValueForm form = chooseValueForm(ScalarType::kInt32, raw.data(), v.size(), 4);
  EXPECT_EQ(form.shift, 3u);
  EXPECT_FALSE(form.exceptions);
  EXPECT_EQ(form.decimals, -1);
  expectRoundTrip(ScalarType::kInt32, raw, form);
  // One odd value among 300: the shift of 3 stays, with exceptions (a bit per value says which).
  v[100] = 7;
  const std::vector<uint8_t> odd = bytesOf(v);
  const ValueForm with_odd = chooseValueForm(ScalarType::kInt32, odd.data(), v.size(), 4);
  EXPECT_EQ(with_odd.shift, 3u);
  EXPECT_TRUE(with_odd.exceptions);
  expectRoundTrip(ScalarType::kInt32, odd, with_odd);
  // Below 64 values the exceptions do not pay: no shift.
  const std::vector<uint8_t> few(odd.begin(), odd.begin() + 4 * 40);
  std::vector<uint8_t> few_odd = few;
  const int32_t seven = 7;
  std::memcpy(&few_odd[4 * 5], &seven, 4);
  EXPECT_EQ(chooseValueForm(ScalarType::kInt32, few_odd.data(), 40, 4).shift, 0u);
}

TEST(ChooseValueForm, MostlyFloat32SumsTakeAShiftWithExceptions) {
  Random r;
  std::vector<double> v(2000);
  for (double& x : v) x = static_cast<double>(static_cast<float>(r.below(1 << 16)) * 1.25f + 3.5f);
  for (size_t i = 0; i < v.size(); i += 97) v[i] += 1e-12;  // a few full doubles
  const std::vector<uint8_t> raw = bytesOf(v);
  const ValueForm form = chooseValueForm(ScalarType::kFloat64, raw.data(), v.size(), 8);
  EXPECT_TRUE(form.exceptions);
  EXPECT_GE(form.shift, 29u);
  expectRoundTrip(ScalarType::kFloat64, raw, form);
}

TEST(ChooseValueForm, FewDistinctValuesTakeATable) {
  Random r;
  const float levels[5] = {-3.25f, 0.1f, 7.0f, 1e6f, 42.42f};
  std::vector<float> v(4096);
  for (float& x : v) x = levels[r.below(5)];
  const std::vector<uint8_t> raw = bytesOf(v);
  const ValueForm form = chooseValueForm(ScalarType::kFloat32, raw.data(), v.size(), 4);
  ASSERT_EQ(form.table.size(), 5u);
  EXPECT_TRUE(std::is_sorted(form.table.begin(), form.table.end()));
  expectRoundTrip(ScalarType::kFloat32, raw, form);
  // Below 1024 values no table is weighed.
  EXPECT_TRUE(chooseValueForm(ScalarType::kFloat32, raw.data(), 1000, 4).table.empty());
}

TEST(ChooseValueForm, AStrideReadsOneComponent) {
  // Component 1 of 3-component items holds the decimals; the others are noise.
  const std::vector<double> d = decimals2(400);
  Random r;
  std::vector<double> items(3 * d.size());
  for (size_t i = 0; i < d.size(); ++i) {
    items[3 * i] = std::ldexp(static_cast<double>(r.next() >> 11), -40);
    items[3 * i + 1] = d[i];
    items[3 * i + 2] = -items[3 * i];
  }
  const std::vector<uint8_t> raw = bytesOf(items);
  EXPECT_EQ(chooseValueForm(ScalarType::kFloat64, raw.data() + 8, d.size(), 24).decimals, 2);
  EXPECT_EQ(chooseValueForm(ScalarType::kFloat64, raw.data(), d.size(), 24).decimals, -1);
}

TEST(ChooseValueForm, OneValueHasOnlyItsShift) {
  const float one = 2.0f;
  const ValueForm form = chooseValueForm(ScalarType::kFloat32, reinterpret_cast<const uint8_t*>(&one), 1, 4);
  EXPECT_EQ(form.shift, 30u);  // 2.0f is 0x40000000
  EXPECT_EQ(form.decimals, -1);
}

// What the decoder says of the declaration `form` of a component of `type` (empty: accepted).
std::string readBack(ScalarType type, ValueForm form) {
  std::vector<uint8_t> stream;
  EntropyCoder<true> enc(&stream);
  ValueFormModels enc_models;
  // Written bit by bit as codeValueForm would, without setting it on a coder (an impossible form is
  // what a corrupt stream says).
  {
    enc.bit(enc_models.table, 0);
    if (isFloatType(type)) {
      enc.bit(enc_models.decimal, form.decimals >= 0);
      if (form.decimals >= 0) enc.direct(static_cast<uint32_t>(form.decimals), 5);
    }
    if (form.decimals < 0) {
      enc.bit(enc_models.shift, 1);
      enc.direct(form.shift, 6);
      enc.bit(enc_models.exceptions, 0);
    }
  }
  enc.finish();
  EntropyCoder<false> dec(stream);
  ValueFormModels models;
  ValueCoder vc(type, 1);
  return codeValueForm(dec, models, vc, type, 0, ValueForm{}, 100);
}

TEST(CodeValueForm, TheDecoderRejectsImpossibleDeclarations) {
  ValueForm too_many;
  too_many.decimals = 30;  // five direct bits hold it; no double has 10^30 exactly
  EXPECT_EQ(readBack(ScalarType::kFloat64, too_many), " declares 30 decimal places (at most 22)");
  ValueForm wide_shift;
  wide_shift.shift = 40;  // wider than a float32
  EXPECT_EQ(readBack(ScalarType::kFloat32, wide_shift), " declares an invalid shift of 40 bits");
  ValueForm fine;
  fine.decimals = 3;
  EXPECT_EQ(readBack(ScalarType::kFloat64, fine), "");
}

}  // namespace
}  // namespace gtn::level
