// libFuzzer target: the whole validator on .gtn images whose checksums the custom mutator re-seals
// after every mutation (reseal.h), so that mutated payloads reach the header, directory and record
// parsers, zstd and the decoders. fuzz_gtn_reader keeps fuzzing the framing and checksum paths.
#include <cstddef>
#include <cstdint>
#include <span>

#include "reseal.h"
#include "validate/validator.h"

extern "C" size_t LLVMFuzzerMutate(uint8_t* data, size_t size, size_t max_size);

extern "C" size_t LLVMFuzzerCustomMutator(uint8_t* data, size_t size, size_t max_size, unsigned int /*seed*/) {
  const size_t n = LLVMFuzzerMutate(data, size, max_size);
  gtn::fuzz::resealGtn(data, n);
  return n;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  gtn::ValidateOptions options;
  options.max_issues = 16;
  const gtn::ValidationReport report = gtn::validateGtnBytes(std::span<const uint8_t>(data, size), "fuzz", options);
  (void)report.hasErrors();
  return 0;
}
