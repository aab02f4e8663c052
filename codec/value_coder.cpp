#include "codec/value_coder.h"

#include <algorithm>
#include <charconv>

namespace gtn {

ValueCoder::ValueCoder(ScalarType type, uint32_t components)
    : type_(type),
      components_(components),
      bits_(scalarBits(type)),
      mask_(bits_ == 64 ? ~uint64_t{0} : ((uint64_t{1} << bits_) - 1)),
      comp_(components) {
  for (Component& c : comp_) c.bucket.resize(kContexts);
}

int ValueCoder::trailingZeros(ScalarType type, const uint8_t* p) {
  uint64_t raw = 0;
  const size_t n = scalarSize(type);
  std::memcpy(&raw, p, n);  // the project assumes a little-endian host
  return raw == 0 ? static_cast<int>(8 * n) : __builtin_ctzll(raw);
}

void ValueCoder::addEscapeModels() {
  if (comp_.size() != components_) return;
  comp_.resize(2 * size_t{components_});
  for (size_t i = components_; i < comp_.size(); ++i) comp_[i].bucket.resize(kContexts);
}

void ValueCoder::setShift(uint32_t comp, int shift, bool exceptions) {
  comp_[comp].shift = shift;
  comp_[comp].exceptions = shift > 0 && exceptions;
  if (comp_[comp].exceptions) addEscapeModels();
}

void ValueCoder::setDecimals(uint32_t comp, int e) {
  comp_[comp].decimals = e;
  if (e >= 0) addEscapeModels();
}

void ValueCoder::setPrinted(uint32_t comp, int digits) {
  comp_[comp].printed = digits;
  if (digits > 0) addEscapeModels();
}

int ValueCoder::decimalPlaces(ScalarType type, uint64_t key, int64_t* n) {
  if (!isFloatType(type)) return -1;
  uint8_t raw[8];
  rawFromKey(type, key, raw);
  // The shortest decimal that reads back as the value has the fewest places, but for the float
  // rounding of n / 10^e at the edges: it only proposes, decimalInteger decides.
  char text[64];
  const auto r =
      type == ScalarType::kFloat32
          ? std::to_chars(text, text + sizeof text, value_detail::loadRaw<float>(raw), std::chars_format::scientific)
          : std::to_chars(text, text + sizeof text, value_detail::loadRaw<double>(raw), std::chars_format::scientific);
  if (r.ec != std::errc()) return -1;
  const char* begin = text;
  const char* e_at = std::find(begin, static_cast<const char*>(r.ptr), 'e');
  const char* dot = std::find(begin, e_at, '.');
  if (e_at == r.ptr) return -1;  // inf, nan
  const int digits_after_point = dot == e_at ? 0 : static_cast<int>(e_at - dot - 1);
  int exponent = 0;  // the text is not NUL-terminated: parse up to r.ptr only
  const char* x = e_at + 1 + (e_at + 1 < r.ptr && e_at[1] == '+');
  if (std::from_chars(x, r.ptr, exponent).ec != std::errc()) return -1;
  for (int e = std::max(0, digits_after_point - exponent), tries = 0; e <= kMaxDecimals && tries < 2; ++e, ++tries)
    if (decimalInteger(type, key, e, n)) return e;
  return -1;
}

}  // namespace gtn
