#include "convert/ascii_rows.h"

#include <cctype>

namespace gtn {

bool readRow(TextReader& reader, std::vector<std::string_view>* tokens) {
  tokens->clear();
  std::string_view token;
  if (!reader.next(&token)) return false;
  tokens->push_back(token);
  while (reader.nextOnLine(&token)) tokens->push_back(token);
  return true;
}

Status checkCountFits(const TextReader& reader, int64_t count, int64_t tokens_per_item, const std::string& what) {
  if (count < 0) return reader.error("negative number of " + what + ": " + std::to_string(count));
  const uint64_t rest = reader.rest().size();
  const uint64_t per_item = 2 * static_cast<uint64_t>(tokens_per_item > 0 ? tokens_per_item : 1);
  // The last token of the file needs no separator, hence the +1.
  if (static_cast<uint64_t>(count) > (rest + 1) / per_item) {
    return reader.error("the header announces " + std::to_string(count) + " " + what + " of " +
                        std::to_string(tokens_per_item) + " values each, but only " + std::to_string(rest) +
                        " bytes follow: the count is wrong or the file is truncated");
  }
  return Status::ok();
}

Status checkRestFits(const TextReader& reader, int64_t announced, int64_t tokens_per_item, const std::string& what,
                     size_t header_line) {
  const uint64_t rest = reader.rest().size();
  const uint64_t per_item = 2 * static_cast<uint64_t>(tokens_per_item > 0 ? tokens_per_item : 1);
  if (announced > 1 && static_cast<uint64_t>(announced - 1) > (rest + 1) / per_item) {
    return invalidData(reader.path() + ":" + std::to_string(header_line) + ": the header announces " +
                       std::to_string(announced) + " " + what + ", rows of " + std::to_string(tokens_per_item) +
                       " values like the first (line " + std::to_string(reader.line()) + "), but only " +
                       std::to_string(rest) + " bytes follow it: the count is wrong or the file is truncated");
  }
  return Status::ok();
}

Status truncatedError(const TextReader& reader, size_t last_line, int64_t done, int64_t total,
                      const std::string& what) {
  return invalidData(reader.path() + ":" + std::to_string(last_line) + ": the file ends after " + std::to_string(done) +
                     " of the " + std::to_string(total) + " " + what + " its header announces");
}

StatusOr<int64_t> parseIntToken(const TextReader& reader, std::string_view token, int64_t lo, int64_t hi,
                                const std::string& what) {
  int64_t v;
  if (!parseInt(token, &v)) return reader.error("expected " + what + " (an integer), found " + quotedToken(token));
  if (v < lo || v > hi) {
    return reader.error(what + " " + std::to_string(v) + " is out of range [" + std::to_string(lo) + ", " +
                        std::to_string(hi) + "]");
  }
  return v;
}

StatusOr<double> parseDoubleToken(const TextReader& reader, std::string_view token, const std::string& what) {
  double v;
  if (!parseDouble(token, &v)) return reader.error("expected " + what + " (a number), found " + quotedToken(token));
  return v;
}

bool sameKeyword(std::string_view token, std::string_view word) {
  if (token.size() != word.size()) return false;
  for (size_t i = 0; i < token.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(token[i])) != std::tolower(static_cast<unsigned char>(word[i])))
      return false;
  }
  return true;
}

}  // namespace gtn
