// Row-oriented reading on top of TextReader, shared by the line-based ASCII importers (TetGen,
// tetrahedral OFF) and the counted sections of Medit: whole rows of tokens, typed token parsing with
// file:line errors, and the check that a count read from a header can fit in what is left of the
// file, made before anything is allocated for it.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "convert/text_reader.h"
#include "mesh/status.h"

namespace gtn {

// Reads the next line that holds a token (blank and comment lines are skipped) into `tokens`, views
// into the reader's text. Returns false at the end of the text. reader.line() is the row's line.
bool readRow(TextReader& reader, std::vector<std::string_view>* tokens);

// Fails unless `count` items of `tokens_per_item` tokens each can fit in the rest of the reader's
// text (a token takes at least two bytes: itself and a separator). `what` names the items ("nodes");
// the error names the file, the line of the count and both numbers. Negative counts fail too.
Status checkCountFits(const TextReader& reader, int64_t count, int64_t tokens_per_item, const std::string& what);
// The same for the items left after the first of `announced` (the row that fixed how wide every row
// is), the error placed at the header's line `header_line` and naming the announced count.
Status checkRestFits(const TextReader& reader, int64_t announced, int64_t tokens_per_item, const std::string& what,
                     size_t header_line);

// The error for a file that ends after `done` of the `total` items (`what`) its header announces,
// placed at `last_line`, the line of the last row read.
Status truncatedError(const TextReader& reader, size_t last_line, int64_t done, int64_t total, const std::string& what);

// `token` as an integer in [lo, hi], or an error at the reader's line naming `what` and the token.
StatusOr<int64_t> parseIntToken(const TextReader& reader, std::string_view token, int64_t lo, int64_t hi,
                                const std::string& what);
// `token` as a double (correctly rounded), or an error at the reader's line.
StatusOr<double> parseDoubleToken(const TextReader& reader, std::string_view token, const std::string& what);

// Whether `token` is the keyword `word`, ignoring ASCII case (Medit's keywords, OFF's header).
bool sameKeyword(std::string_view token, std::string_view word);

}  // namespace gtn
