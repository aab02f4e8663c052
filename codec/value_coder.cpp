#include "codec/value_coder.h"

#include <cmath>
#include <cstring>

namespace gtn {

namespace {
template <class T>
T loadRaw(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
template <class T>
void storeRaw(uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof(T));
}
// Rounds to the nearest integer and clamps to [lo, hi] without undefined conversions.
double clampRound(double v, double lo, double hi) {
  if (!(v == v)) return 0.0;
  v = std::nearbyint(v);
  if (v < lo) return lo;
  if (v > hi) return hi;
  return v;
}
}  // namespace

int scalarBits(ScalarType type) { return static_cast<int>(8 * scalarSize(type)); }

uint64_t keyFromRaw(ScalarType type, const uint8_t* p) {
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

void rawFromKey(ScalarType type, uint64_t key, uint8_t* p) {
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

uint64_t keyFromPrediction(ScalarType type, double v) {
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

double doubleFromRaw(ScalarType type, const uint8_t* p) {
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

ValueCoder::ValueCoder(ScalarType type, uint32_t components)
    : type_(type),
      components_(components),
      bits_(scalarBits(type)),
      mask_(bits_ == 64 ? ~uint64_t{0} : ((uint64_t{1} << bits_) - 1)),
      comp_(components) {
  for (Component& c : comp_) c.bucket.resize(kContexts);
}

}  // namespace gtn
