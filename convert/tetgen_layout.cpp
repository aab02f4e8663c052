#include "convert/tetgen_layout.h"

#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "convert/text_reader.h"

namespace gtn::tetgen {

namespace {
bool plainByte(unsigned char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.' ||
         c == '+' || c == '-';
}

int hexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

template <class T>
void appendNumber(std::string* out, T v) {
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  (void)ec;  // 64 bytes hold any shortest float/double/integer text
  out->append(buf, end);
}

template <class Bits>
void appendNan(std::string* out, Bits bits) {
  char buf[32];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, bits, 16);
  (void)ec;
  out->append("nan(0x");
  out->append(buf, end);
  out->push_back(')');
}

// "nan(0xBITS)" with a NaN bit pattern of `Bits` width.
template <class Bits>
bool parseNanBits(std::string_view token, Bits* bits) {
  if (token.size() < 8 || token.substr(0, 6) != "nan(0x" || token.back() != ')') return false;
  const std::string_view hex = token.substr(6, token.size() - 7);
  auto [ptr, ec] = std::from_chars(hex.data(), hex.data() + hex.size(), *bits, 16);
  return ec == std::errc() && ptr == hex.data() + hex.size() && !hex.empty();
}

template <class T>
bool parseIntegral(std::string_view token, uint8_t* value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  T v;
  auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
  if (ec != std::errc() || ptr != token.data() + token.size() || token.empty()) return false;
  std::memcpy(value, &v, sizeof v);
  return true;
}

template <class T>
void appendStored(std::string* out, const uint8_t* value) {
  T v;
  std::memcpy(&v, value, sizeof v);
  appendNumber(out, v);
}
}  // namespace

std::string basePath(const std::string& path) {
  for (const std::string ext : {".node", ".ele", ".face"}) {
    if (path.size() > ext.size() && path.compare(path.size() - ext.size(), ext.size(), ext) == 0)
      return path.substr(0, path.size() - ext.size());
  }
  return path;
}

std::array<uint32_t, 3> sortedTriangle(uint32_t a, uint32_t b, uint32_t c) {
  if (a > b) std::swap(a, b);
  if (b > c) std::swap(b, c);
  if (a > b) std::swap(a, b);
  return {a, b, c};
}

std::string escapeText(std::string_view text) {
  static const char kHex[] = "0123456789ABCDEF";
  std::string out;
  out.reserve(text.size());
  for (char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (plainByte(c)) {
      out.push_back(ch);
    } else {
      out.push_back('%');
      out.push_back(kHex[c >> 4]);
      out.push_back(kHex[c & 15]);
    }
  }
  return out;
}

bool unescapeText(std::string_view text, std::string* out) {
  out->clear();
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '%') {
      out->push_back(text[i]);
      continue;
    }
    if (i + 2 >= text.size()) return false;
    const int hi = hexDigit(text[i + 1]), lo = hexDigit(text[i + 2]);
    if (hi < 0 || lo < 0) return false;
    out->push_back(static_cast<char>(hi * 16 + lo));
    i += 2;
  }
  return true;
}

std::string formatFieldList(const std::vector<ColumnField>& fields, std::string_view tag) {
  std::string out;
  for (const ColumnField& f : fields) {
    if (!out.empty()) out.push_back(' ');
    out += escapeText(f.name) + ":" + std::to_string(f.components) + ":" + scalarTypeName(f.type);
    if (f.tagged) {
      out.push_back(':');
      out.append(tag);
    }
  }
  return out;
}

bool parseFieldList(std::string_view text, std::string_view tag, std::vector<ColumnField>* fields, std::string* why) {
  fields->clear();
  TextReader reader("", text, '\0');
  std::string_view item;
  while (reader.next(&item)) {
    std::vector<std::string_view> parts;
    size_t start = 0;
    for (size_t i = 0; i <= item.size(); ++i) {
      if (i == item.size() || item[i] == ':') {
        parts.push_back(item.substr(start, i - start));
        start = i + 1;
      }
    }
    ColumnField f;
    int64_t components = 0;
    if (parts.size() < 3 || parts.size() > 4 || !unescapeText(parts[0], &f.name) || !parseInt(parts[1], &components) ||
        components < 1 || components > (1 << 20) || !scalarTypeFromName(std::string(parts[2]), &f.type) ||
        (parts.size() == 4 && parts[3] != tag)) {
      *why = "malformed field description '" + std::string(item.substr(0, 80)) + "' (expected NAME:COMPONENTS:TYPE" +
             (tag.empty() ? "" : "[:" + std::string(tag) + "]") + ")";
      return false;
    }
    f.components = static_cast<uint32_t>(components);
    f.tagged = parts.size() == 4;
    fields->push_back(std::move(f));
  }
  return true;
}

std::vector<Comment> leadingComments(std::string_view text) {
  std::vector<Comment> out;
  size_t pos = 0, line = 1;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view row = trim(text.substr(pos, end - pos));
    if (!row.empty()) {
      if (row.front() != '#') break;
      const std::string_view body = trim(row.substr(1));
      for (std::string_view key : {kCoordinatesKey, kPointFieldsKey, kCellFieldsKey, kMetadataKey}) {
        if (body.substr(0, key.size()) == key) out.push_back({line, key, trim(body.substr(key.size()))});
      }
    }
    pos = end + 1;
    ++line;
  }
  return out;
}

void appendValue(std::string* out, ScalarType type, const uint8_t* value) {
  switch (type) {
    case ScalarType::kInt8: appendStored<int8_t>(out, value); return;
    case ScalarType::kUInt8: appendStored<uint8_t>(out, value); return;
    case ScalarType::kInt16: appendStored<int16_t>(out, value); return;
    case ScalarType::kUInt16: appendStored<uint16_t>(out, value); return;
    case ScalarType::kInt32: appendStored<int32_t>(out, value); return;
    case ScalarType::kUInt32: appendStored<uint32_t>(out, value); return;
    case ScalarType::kInt64: appendStored<int64_t>(out, value); return;
    case ScalarType::kUInt64: appendStored<uint64_t>(out, value); return;
    case ScalarType::kFloat32: {
      float v;
      std::memcpy(&v, value, sizeof v);
      if (std::isnan(v)) {
        uint32_t bits;
        std::memcpy(&bits, value, sizeof bits);
        appendNan(out, bits);
      } else {
        appendNumber(out, v);
      }
      return;
    }
    case ScalarType::kFloat64: {
      double v;
      std::memcpy(&v, value, sizeof v);
      if (std::isnan(v)) {
        uint64_t bits;
        std::memcpy(&bits, value, sizeof bits);
        appendNan(out, bits);
      } else {
        appendNumber(out, v);
      }
      return;
    }
  }
}

bool parseValue(std::string_view token, ScalarType type, uint8_t* value) {
  switch (type) {
    case ScalarType::kInt8:
    case ScalarType::kInt16:
    case ScalarType::kInt32: {
      int64_t v;
      if (!parseInt(token, &v)) return false;
      const int bits = static_cast<int>(scalarSize(type)) * 8;
      const int64_t lo = -(int64_t{1} << (bits - 1)), hi = (int64_t{1} << (bits - 1)) - 1;
      if (v < lo || v > hi) return false;
      // Little-endian: the low bytes of the int64 are the narrower value.
      std::memcpy(value, &v, scalarSize(type));
      return true;
    }
    case ScalarType::kUInt8:
    case ScalarType::kUInt16:
    case ScalarType::kUInt32: {
      int64_t v;
      if (!parseInt(token, &v)) return false;
      const int bits = static_cast<int>(scalarSize(type)) * 8;
      if (v < 0 || v > (int64_t{1} << bits) - 1) return false;
      std::memcpy(value, &v, scalarSize(type));
      return true;
    }
    case ScalarType::kInt64: return parseIntegral<int64_t>(token, value);
    case ScalarType::kUInt64: return parseIntegral<uint64_t>(token, value);
    case ScalarType::kFloat32: {
      uint32_t bits;
      if (parseNanBits(token, &bits)) {
        float v;
        std::memcpy(&v, &bits, sizeof v);
        if (!std::isnan(v)) return false;
        std::memcpy(value, &bits, sizeof bits);
        return true;
      }
      float v;
      if (!parseFloat(token, &v)) return false;
      std::memcpy(value, &v, sizeof v);
      return true;
    }
    case ScalarType::kFloat64: {
      uint64_t bits;
      if (parseNanBits(token, &bits)) {
        double v;
        std::memcpy(&v, &bits, sizeof v);
        if (!std::isnan(v)) return false;
        std::memcpy(value, &bits, sizeof bits);
        return true;
      }
      double v;
      if (!parseDouble(token, &v)) return false;
      std::memcpy(value, &v, sizeof v);
      return true;
    }
  }
  return false;
}

}  // namespace gtn::tetgen
