#include "convert/text_reader.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

namespace gtn {

namespace {
bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// Whether `token` (a decimal beyond T's range) is T's largest finite value, in magnitude, rounded to
// the token's own number of significant digits: a writer that prints doubles with fewer than 17
// digits turns DBL_MAX into a decimal above it (VTK's legacy ASCII writer, %.11lg, prints
// 1.7976931349e+308, which VTK itself then refuses).
template <class T>
bool isRoundedMax(std::string_view token) {
  if (!token.empty() && (token.front() == '-' || token.front() == '+')) token.remove_prefix(1);
  const size_t e = token.find_first_of("eE");
  const std::string_view mantissa = token.substr(0, e);
  int digits = 0;
  bool leading = true;
  for (const char c : mantissa) {
    if (c < '0' || c > '9') continue;
    if (c != '0') leading = false;
    if (!leading) ++digits;
  }
  // Trailing zeros of a mantissa with a point are significant too ("1.80e308" has 3 digits); a
  // count beyond 17 is no rounding of a double.
  if (digits < 1 || digits > 17) return false;
  char max[40];
  std::snprintf(max, sizeof max, "%.*e", digits - 1, static_cast<double>(std::numeric_limits<T>::max()));
  long double a, b;
  const auto [pa, ea] = std::from_chars(token.data(), token.data() + token.size(), a);
  const auto [pb, eb] = std::from_chars(max, max + std::strlen(max), b);
  return ea == std::errc() && eb == std::errc() && pa == token.data() + token.size() && a == b;
}

template <class T>
bool parseFloating(std::string_view token, T* out) {
  if (token.empty()) return false;
  if (token.front() == '+') token.remove_prefix(1);  // from_chars rejects a leading plus
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, *out);
  if (ec == std::errc::result_out_of_range && ptr == end) {
    // Underflow reads as strtod reads it: a float below FLT_MIN as its float subnormal, anything
    // below the smallest subnormal as a signed zero (TetGen writes values such as 1.6e-322, and
    // files declare as float values that only a double holds). Overflow stays an error, unless the
    // token is the largest value printed with fewer digits (isRoundedMax).
    double d;
    auto [dptr, dec] = std::from_chars(token.data(), end, d);
    if (dec == std::errc() && dptr == end && std::fabs(d) < 1) {
      *out = static_cast<T>(d);
      return true;
    }
    const size_t e = token.find_last_of("eE");
    if (dec == std::errc::result_out_of_range && e != std::string_view::npos && e + 1 < token.size() &&
        token[e + 1] == '-') {
      *out = token.front() == '-' ? -T(0) : T(0);
      return true;
    }
    if (isRoundedMax<T>(token)) {
      *out = token.front() == '-' ? -std::numeric_limits<T>::max() : std::numeric_limits<T>::max();
      return true;
    }
    return false;
  }
  return ec == std::errc() && ptr == end;
}
}  // namespace

std::string quotedToken(std::string_view token) {
  std::string s(token.substr(0, 40));
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return "'" + s + (token.size() > 40 ? "...'" : "'");
}

bool parseInt(std::string_view token, int64_t* out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, *out);
  return ec == std::errc() && ptr == end && !token.empty();
}

bool parseDouble(std::string_view token, double* out) { return parseFloating(token, out); }
bool parseFloat(std::string_view token, float* out) { return parseFloating(token, out); }

void TextReader::skipSpace(bool stop_at_newline) {
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (lineBreakAt(pos_)) {
      if (stop_at_newline) return;
      ++line_;
      ++pos_;
    } else if (isSpace(c)) {
      ++pos_;
    } else if (comment_ != '\0' && c == comment_) {
      while (pos_ < text_.size() && !lineBreakAt(pos_)) ++pos_;
    } else {
      return;
    }
  }
}

bool TextReader::next(std::string_view* token) {
  skipSpace(false);
  if (pos_ >= text_.size()) {
    token_line_ = line_;
    return false;
  }
  const size_t start = pos_;
  while (pos_ < text_.size() && !isSpace(text_[pos_]) && !(comment_ != '\0' && text_[pos_] == comment_)) ++pos_;
  token_line_ = line_;
  *token = text_.substr(start, pos_ - start);
  return true;
}

bool TextReader::nextOnLine(std::string_view* token) {
  skipSpace(true);
  if (pos_ >= text_.size() || lineBreakAt(pos_)) return false;
  return next(token);
}

void TextReader::skipLine() {
  while (pos_ < text_.size() && !lineBreakAt(pos_)) ++pos_;
  if (pos_ < text_.size()) {
    ++pos_;
    ++line_;
  }
}

bool TextReader::atEnd() {
  skipSpace(false);
  return pos_ >= text_.size();
}

void TextReader::seek(size_t offset) {
  for (size_t i = pos_; i < offset && i < text_.size(); ++i)
    if (lineBreakAt(i)) ++line_;
  pos_ = offset;
}

Status TextReader::error(const std::string& reason) const {
  return invalidData(path_ + ":" + std::to_string(token_line_) + ": " + reason);
}

Status TextReader::errorAtEnd(const char* what) const {
  return invalidData(path_ + ":" + std::to_string(token_line_) + ": file ends where " + what + " was expected");
}

StatusOr<int64_t> TextReader::readInt(const char* what) {
  std::string_view tok;
  if (!next(&tok)) return errorAtEnd(what);
  int64_t v;
  if (!parseInt(tok, &v)) return error("expected " + std::string(what) + " (an integer), found " + quotedToken(tok));
  return v;
}

StatusOr<double> TextReader::readDouble(const char* what) {
  std::string_view tok;
  if (!next(&tok)) return errorAtEnd(what);
  double v;
  if (!parseDouble(tok, &v)) return error("expected " + std::string(what) + " (a number), found " + quotedToken(tok));
  return v;
}

StatusOr<float> TextReader::readFloat(const char* what) {
  std::string_view tok;
  if (!next(&tok)) return errorAtEnd(what);
  float v;
  if (!parseFloat(tok, &v)) return error("expected " + std::string(what) + " (a number), found " + quotedToken(tok));
  return v;
}

}  // namespace gtn
