// What the whole-file fuzz targets (fuzz_gtn_reader, fuzz_gtn_sealed) do with an input: the whole
// validator, which runs the .gtn reader (prefix, framing, checksums, directory), the level decoder,
// the merge-tree decoder and every check. Any crash, sanitizer report, leak, hang or unbounded
// allocation is a bug; a clean Status or report is success.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "validate/validator.h"

namespace gtn::fuzz {

inline void validateFuzzInput(const uint8_t* data, size_t size) {
  ValidateOptions options;
  options.max_issues = 16;
  const ValidationReport report = validateGtnBytes(std::span<const uint8_t>(data, size), "fuzz", options);
  (void)report.hasErrors();
}

}  // namespace gtn::fuzz
