// libFuzzer target: the log reader again, behind a custom mutator that repairs the header and
// block CRCs after every mutation. Random bytes almost never carry a valid CRC-32, so without
// it nearly every mutant of a valid log stops at the first checksum; with it the fuzzer
// explores the lengths, counts and block sequence the checksums protect.
#include <cstddef>
#include <cstdint>

#include "support/log_oracle.h"

// libFuzzer's own mutations, for a custom mutator to build on.
extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size,
                                               std::size_t max_size, unsigned int /*seed*/) {
  // LLVMFuzzerMutate draws from libFuzzer's generator, which -seed already makes repeatable.
  size = LLVMFuzzerMutate(data, size, max_size);
  hapticd::fuzz::fix_log_crcs({data, size});
  return size;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hapticd::fuzz::check_log_read({data, size});
  return 0;
}
