// libFuzzer target: the whole validator on arbitrary bytes (fuzz_validate.h), so mostly the framing
// and checksum paths; fuzz_gtn_sealed re-seals checksums to reach what lies behind them.
#include "fuzz_validate.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  gtn::fuzz::validateFuzzInput(data, size);
  return 0;
}
