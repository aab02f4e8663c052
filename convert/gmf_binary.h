// libMeshb's binary layout (GMF), shared by the .meshb and .solb readers (libMeshb 7 documentation and
// reference reader, LoicMarechal/libMeshb):
//   int32  code      1, written in the writer's byte order: read as 0x01000000 the file is byte-swapped
//   int32  version   1: 32-bit reals, integers and positions; 2: 64-bit reals; 3: 64-bit reals and
//                    positions; 4: 64-bit reals, positions and integers
//   then keyword records, each:
//   int32  keyword   its code (GmfDimension 3, GmfVertices 4, GmfEnd 54, GmfSolAtVertices 62, ...)
//   pos    next      the absolute byte offset of the next keyword record, 0 after the last one
//   then the keyword's data (read by the caller).
// Every read is checked against the bytes left before the next keyword (or the end of the file).
#pragma once

#include <cstdint>
#include <cstring>
#include <string>

#include "mesh/status.h"

namespace gtn {

class GmfBinary {
 public:
  GmfBinary(const std::string& path, const std::string& bytes) : path_(path), bytes_(bytes) {}

  // Reads the code and the version; a file that is not GMF binary is kNotOurFile. `kind` names the
  // file type in messages (".meshb", ".solb").
  Status open(const char* kind);
  int version() const { return version_; }
  size_t intSize() const { return int_size_; }    // element counts and indices (8 in version 4)
  size_t realSize() const { return real_size_; }  // 4 in version 1, else 8

  // The next keyword record: its code, where it starts and where its data ends (the next record, or
  // the end of the file). False at the End keyword, after the last record or at the end of the file.
  StatusOr<bool> nextKeyword(uint32_t* code, uint64_t* at, uint64_t* end);

  // The Dimension keyword's value (an int32 in every version), which must be 3; `why` completes the
  // error for another ("only 3D solutions are read").
  Status readDimension3(uint64_t at, uint64_t end, const std::string& why);
  // Fails unless `n` bytes from the read position lie before `end`.
  Status need(uint64_t n, const std::string& what, uint64_t end) const;
  Status fail(uint64_t at, const std::string& reason) const {
    return invalidData(path_ + ": byte offset " + std::to_string(at) + ": " + reason);
  }
  uint64_t position() const { return pos_; }
  uint64_t size() const { return bytes_.size(); }

  // Unchecked reads (after need()): a `size`-byte word in the file's byte order, an int of the
  // version's integer size (sign-extended), a real of its real size.
  uint64_t word(size_t size) {
    uint64_t v = 0;
    for (size_t i = 0; i < size; ++i)
      v |= static_cast<uint64_t>(static_cast<uint8_t>(bytes_[pos_ + (swap_ ? size - 1 - i : i)])) << (8 * i);
    pos_ += size;
    return v;
  }
  int64_t integer() {
    const uint64_t v = word(int_size_);
    return int_size_ == 4 ? static_cast<int64_t>(static_cast<int32_t>(v)) : static_cast<int64_t>(v);
  }
  double real() {
    const uint64_t v = word(real_size_);
    if (real_size_ == 4) {
      const uint32_t u = static_cast<uint32_t>(v);
      float f;
      std::memcpy(&f, &u, 4);
      return f;
    }
    double d;
    std::memcpy(&d, &v, 8);
    return d;
  }
  // A real's bytes in host order, for copying into a field of the same width.
  uint64_t realBits() { return word(real_size_); }

 private:
  const std::string& path_;
  const std::string& bytes_;
  uint64_t pos_ = 0;
  uint64_t next_ = 0;  // the next keyword record, 0 before the first
  bool done_ = false;
  bool swap_ = false;
  int version_ = 0;
  size_t int_size_ = 4, real_size_ = 4, pos_size_ = 4;
};

}  // namespace gtn
