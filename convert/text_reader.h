// A tokenizer over a text file held in memory, shared by the ASCII importers (TetGen, Medit, OFF,
// legacy VTK). Whitespace of any kind separates tokens; a comment character hides the rest of a line.
// Numbers are parsed with std::from_chars (correctly rounded, so text written with enough digits reads
// back bit-exact). Every error names the file and the line.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "mesh/status.h"

namespace gtn {

class TextReader {
 public:
  // `comment` = '\0' for formats without comments. A UTF-8 byte order mark at the start is skipped
  // (editors on Windows write one). Lines end with LF, CR LF or a lone CR (classic Mac OS).
  TextReader(std::string path, std::string_view text, char comment = '#')
      : path_(std::move(path)), text_(text), comment_(comment) {
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;
  }

  // Next token, or false at the end of the text.
  bool next(std::string_view* token);
  // Next token on the current line only (does not cross a newline); false if the line has no more.
  bool nextOnLine(std::string_view* token);
  // Skips the rest of the current line.
  void skipLine();
  bool atEnd();

  // Reads the next token as a number; `what` says what was expected ("node count").
  StatusOr<int64_t> readInt(const char* what);
  StatusOr<double> readDouble(const char* what);
  StatusOr<float> readFloat(const char* what);

  // 1-based line of the last token returned (or of the current position before any).
  size_t line() const { return token_line_; }
  size_t offset() const { return pos_; }
  const std::string& path() const { return path_; }
  std::string_view rest() const { return text_.substr(pos_); }
  void seek(size_t offset);

  // "path:line: reason"
  Status error(const std::string& reason) const;
  Status errorAtEnd(const char* what) const;

 private:
  void skipSpace(bool stop_at_newline);
  // Whether a line ends at text_[i]: LF, or CR not followed by LF (CR LF ends at its LF).
  bool lineBreakAt(size_t i) const {
    return text_[i] == '\n' || (text_[i] == '\r' && (i + 1 == text_.size() || text_[i + 1] != '\n'));
  }

  std::string path_;
  std::string_view text_;
  char comment_;
  size_t pos_ = 0;
  size_t line_ = 1;
  size_t token_line_ = 1;
};

// A token for an error message: quoted, cut to 40 characters, bytes outside printable ASCII shown as '?'.
std::string quotedToken(std::string_view token);

// Parses a whole token as a number; false when the token is not exactly a number.
bool parseInt(std::string_view token, int64_t* out);
bool parseDouble(std::string_view token, double* out);
bool parseFloat(std::string_view token, float* out);

}  // namespace gtn
