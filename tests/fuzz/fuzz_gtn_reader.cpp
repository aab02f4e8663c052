// libFuzzer target: the whole validator on arbitrary bytes, which runs the .gtn reader (prefix,
// framing, checksums, directory), the level decoder, the merge-tree decoder and every check. Any crash,
// sanitizer report, leak, hang or unbounded allocation is a bug; a clean Status or report is success.
#include <cstddef>
#include <cstdint>
#include <span>

#include "validate/validator.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  gtn::ValidateOptions options;
  options.max_issues = 16;
  const gtn::ValidationReport report = gtn::validateGtnBytes(std::span<const uint8_t>(data, size), "fuzz", options);
  (void)report.hasErrors();
  return 0;
}
