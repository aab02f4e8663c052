// Byte-level encodings of the .gtn container (spec/gtn-format.md, "Conventions"): little-endian fixed
// width integers and IEEE 754 doubles, unsigned LEB128 varints (shortest form only), and strings as a
// varint byte length followed by UTF-8 bytes.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "mesh/status.h"

namespace gtn {

// Appends encoded values to a byte vector.
class ByteWriter {
 public:
  void u8(uint8_t v) { bytes_.push_back(v); }
  void u16(uint16_t v);
  void u32(uint32_t v);
  void u64(uint64_t v);
  void f64(double v);  // the IEEE 754 bit pattern, little-endian
  void varint(uint64_t v);
  void string(const std::string& s);
  void raw(std::span<const uint8_t> data) { bytes_.insert(bytes_.end(), data.begin(), data.end()); }
  void raw(const void* data, size_t size);

  std::vector<uint8_t>& bytes() { return bytes_; }
  size_t size() const { return bytes_.size(); }

 private:
  std::vector<uint8_t> bytes_;
};

// Reads encoded values from a byte span that sits at `base_offset` in a file. Every failure is
// kInvalidData with a message "<what>: byte offset <N>: <reason>", N being the absolute file offset
// of the value that could not be read.
class ByteReader {
 public:
  ByteReader(std::span<const uint8_t> data, uint64_t base_offset, std::string what)
      : data_(data), base_(base_offset), what_(std::move(what)) {}

  Status u8(uint8_t* v, const char* name);
  Status u16(uint16_t* v, const char* name);
  Status u64(uint64_t* v, const char* name);
  Status f64(double* v, const char* name);
  // Rejects varints longer than 10 bytes, values above 2^64-1 and non-shortest encodings.
  Status varint(uint64_t* v, const char* name);
  // A varint bounded by `max` (inclusive); the message names `name` and the bound.
  Status varintAtMost(uint64_t* v, uint64_t max, const char* name);
  // Length-prefixed string; the length is checked against the remaining bytes before allocating.
  Status string(std::string* s, const char* name);
  Status bytes(std::span<const uint8_t>* out, size_t n, const char* name);

  size_t remaining() const { return data_.size() - pos_; }
  uint64_t offset() const { return base_ + pos_; }  // absolute offset of the next byte
  bool atEnd() const { return pos_ == data_.size(); }
  // Fails unless every byte was consumed ("<n> unexpected bytes at the end of <context>").
  Status expectEnd(const char* context) const;
  // An error at the current offset.
  Status error(const std::string& reason) const;
  Status errorAt(uint64_t offset, const std::string& reason) const;

 private:
  Status need(size_t n, const char* name);

  std::span<const uint8_t> data_;
  size_t pos_ = 0;
  uint64_t base_;
  std::string what_;
};

}  // namespace gtn
