// libFuzzer target below the container's checksums: arbitrary bytes straight into the level decoder
// and the merge-tree decoder, which a checksummed file only reaches with valid chunks. The input
// layout is in fuzz_decoder_input.h; tests/fuzz/corpus-decoder holds this target's corpus.
#include <cstddef>
#include <cstdint>

#include "fuzz_decoder_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  (void)gtn::fuzz::decodeFuzzInput(data, size);
  return 0;
}
