// libFuzzer target: the whole validator on .gtn images whose checksums the custom mutator re-seals
// after every mutation (reseal.h), so that mutated payloads reach the header, directory and record
// parsers, zstd and the decoders. fuzz_gtn_reader keeps fuzzing the framing and checksum paths.
#include <cstddef>
#include <cstdint>

#include "fuzz_validate.h"
#include "reseal.h"

extern "C" size_t LLVMFuzzerMutate(uint8_t* data, size_t size, size_t max_size);

extern "C" size_t LLVMFuzzerCustomMutator(uint8_t* data, size_t size, size_t max_size, unsigned int /*seed*/) {
  const size_t n = LLVMFuzzerMutate(data, size, max_size);
  gtn::fuzz::resealGtn(data, n);
  return n;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  gtn::fuzz::validateFuzzInput(data, size);
  return 0;
}
