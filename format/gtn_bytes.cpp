#include "format/gtn_bytes.h"

#include <cstring>

namespace gtn {

void ByteWriter::u16(uint16_t v) {
  for (int i = 0; i < 2; ++i) bytes_.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
void ByteWriter::u32(uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes_.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
void ByteWriter::u64(uint64_t v) {
  for (int i = 0; i < 8; ++i) bytes_.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
void ByteWriter::f64(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, 8);
  u64(bits);
}
void ByteWriter::varint(uint64_t v) {
  while (v >= 0x80) {
    bytes_.push_back(static_cast<uint8_t>(v | 0x80));
    v >>= 7;
  }
  bytes_.push_back(static_cast<uint8_t>(v));
}
void ByteWriter::string(const std::string& s) {
  varint(s.size());
  raw(s.data(), s.size());
}
void ByteWriter::raw(const void* data, size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  bytes_.insert(bytes_.end(), p, p + size);
}

Status ByteReader::errorAt(uint64_t offset, const std::string& reason) const {
  return invalidData(what_ + ": byte offset " + std::to_string(offset) + ": " + reason);
}
Status ByteReader::error(const std::string& reason) const { return errorAt(offset(), reason); }

Status ByteReader::need(size_t n, const char* name) {
  if (remaining() < n)
    return error(std::string("truncated ") + name + ": needs " + std::to_string(n) + " bytes, " +
                 std::to_string(remaining()) + " remain");
  return Status::ok();
}

Status ByteReader::u8(uint8_t* v, const char* name) {
  GTN_RETURN_IF_ERROR(need(1, name));
  *v = data_[pos_++];
  return Status::ok();
}
Status ByteReader::u16(uint16_t* v, const char* name) {
  GTN_RETURN_IF_ERROR(need(2, name));
  *v = static_cast<uint16_t>(data_[pos_] | (data_[pos_ + 1] << 8));
  pos_ += 2;
  return Status::ok();
}
Status ByteReader::u64(uint64_t* v, const char* name) {
  GTN_RETURN_IF_ERROR(need(8, name));
  uint64_t r = 0;
  for (int i = 7; i >= 0; --i) r = (r << 8) | data_[pos_ + i];
  pos_ += 8;
  *v = r;
  return Status::ok();
}
Status ByteReader::f64(double* v, const char* name) {
  uint64_t bits;
  GTN_RETURN_IF_ERROR(u64(&bits, name));
  std::memcpy(v, &bits, 8);
  return Status::ok();
}

Status ByteReader::varint(uint64_t* v, const char* name) {
  const uint64_t start = offset();
  uint64_t r = 0;
  for (int i = 0; i < 10; ++i) {
    if (atEnd()) return errorAt(start, std::string("truncated varint ") + name);
    const uint8_t b = data_[pos_++];
    if (i == 9 && b > 1) return errorAt(start, std::string("varint ") + name + " exceeds 64 bits");
    r |= static_cast<uint64_t>(b & 0x7F) << (7 * i);
    if (!(b & 0x80)) {
      if (i > 0 && b == 0) return errorAt(start, std::string("varint ") + name + " is not in shortest form");
      *v = r;
      return Status::ok();
    }
  }
  return errorAt(start, std::string("varint ") + name + " is longer than 10 bytes");
}

Status ByteReader::varintAtMost(uint64_t* v, uint64_t max, const char* name) {
  const uint64_t start = offset();
  GTN_RETURN_IF_ERROR(varint(v, name));
  if (*v > max)
    return errorAt(start,
                   std::string(name) + " " + std::to_string(*v) + " exceeds the limit of " + std::to_string(max));
  return Status::ok();
}

Status ByteReader::string(std::string* s, const char* name) {
  uint64_t n;
  const uint64_t start = offset();
  GTN_RETURN_IF_ERROR(varint(&n, name));
  if (n > remaining())
    return errorAt(start, std::string(name) + " declares " + std::to_string(n) + " bytes but only " +
                              std::to_string(remaining()) + " remain in the chunk");
  s->assign(reinterpret_cast<const char*>(data_.data() + pos_), n);
  pos_ += n;
  return Status::ok();
}

Status ByteReader::bytes(std::span<const uint8_t>* out, size_t n, const char* name) {
  GTN_RETURN_IF_ERROR(need(n, name));
  *out = data_.subspan(pos_, n);
  pos_ += n;
  return Status::ok();
}

Status ByteReader::expectEnd(const char* context) const {
  if (!atEnd()) return error(std::to_string(remaining()) + " unexpected bytes at the end of " + context);
  return Status::ok();
}

}  // namespace gtn
