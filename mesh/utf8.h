// Text that leaves the program (the .gtn format's strings, JSON output) is UTF-8; names read from
// files are bytes in whatever encoding the writing tool used.
#pragma once

#include <string>
#include <string_view>

namespace gtn {

// True when `s` is well-formed UTF-8 (shortest forms, no surrogates, at most U+10FFFF).
bool isValidUtf8(std::string_view s);
// `s` itself when it is valid UTF-8; otherwise its bytes read as Latin-1 (ISO 8859-1, the usual
// encoding of such names in older files), each byte above 0x7F becoming its two-byte UTF-8 form.
std::string toUtf8(std::string_view s);

}  // namespace gtn
