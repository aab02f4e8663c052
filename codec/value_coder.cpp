#include "codec/value_coder.h"

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

}  // namespace gtn
