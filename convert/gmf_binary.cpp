#include "convert/gmf_binary.h"

namespace gtn {

namespace {
constexpr uint32_t kEnd = 54;  // GmfEnd
}  // namespace

Status GmfBinary::open(const char* kind) {
  if (bytes_.size() < 8)
    return Status(StatusCode::kNotOurFile, path_ + ": " + std::to_string(bytes_.size()) + " bytes: too short for a " +
                                               kind + " header (code and version)");
  const uint64_t code = word(4);
  if (code == 0x01000000u) {
    swap_ = true;
  } else if (code != 1) {
    return Status(StatusCode::kNotOurFile, path_ + ": byte offset 0: not a " + kind + " file: its first word is " +
                                               std::to_string(code) + ", not 1 in either byte order");
  }
  const uint64_t version = word(4);
  if (version < 1 || version > 4)
    return unsupported(path_ + ": byte offset 4: " + kind + " version " + std::to_string(version) +
                       " is not supported (known: 1 to 4)");
  version_ = static_cast<int>(version);
  real_size_ = version == 1 ? 4 : 8;
  pos_size_ = version >= 3 ? 8 : 4;
  int_size_ = version == 4 ? 8 : 4;
  return Status::ok();
}

Status GmfBinary::need(uint64_t n, const std::string& what, uint64_t end) const {
  if (pos_ > end || n > end - pos_) {
    return fail(pos_, what + " needs " + std::to_string(n) + " bytes but " +
                          (end < bytes_.size() ? "the next keyword starts at byte offset " + std::to_string(end)
                                               : "the file ends at byte offset " + std::to_string(bytes_.size())));
  }
  return Status::ok();
}

Status GmfBinary::readDimension3(uint64_t at, uint64_t end, const std::string& why) {
  GTN_RETURN_IF_ERROR(need(4, "Dimension", end));
  const int64_t d = static_cast<int32_t>(word(4));
  if (d != 3) return fail(at, "dimension " + std::to_string(d) + ": " + why);
  return Status::ok();
}

StatusOr<bool> GmfBinary::nextKeyword(uint32_t* code, uint64_t* at, uint64_t* end) {
  if (done_) return false;
  if (next_ != 0) pos_ = next_;
  if (pos_ >= bytes_.size()) return false;
  *at = pos_;
  GTN_RETURN_IF_ERROR(need(4 + pos_size_, "a keyword header (code and next-keyword position)", bytes_.size()));
  *code = static_cast<uint32_t>(word(4));
  const uint64_t next = word(pos_size_);
  if (*code == kEnd) {
    done_ = true;
    return false;
  }
  if (next != 0 && (next <= *at || next > bytes_.size()))
    return fail(*at, "keyword " + std::to_string(*code) + " says the next keyword is at byte offset " +
                         std::to_string(next) + ", outside (" + std::to_string(*at) + ", " +
                         std::to_string(bytes_.size()) + "]");
  done_ = next == 0;  // the last keyword
  next_ = next;
  *end = next != 0 ? next : bytes_.size();
  return true;
}

}  // namespace gtn
