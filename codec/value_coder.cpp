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

}  // namespace gtn
