// Counts heap allocations made by the calling thread, so a test can prove that an RT path
// allocates nothing (in the spirit of Drake's LimitMalloc). Linking this library replaces the
// global operator new; without sanitizers it also interposes malloc/calloc/realloc, so
// allocations made inside C libraries are caught too.
#pragma once

#include <cstdint>

namespace hapticd::testing {

// Allocations made so far by the calling thread.
std::uint64_t thread_allocations() noexcept;

// True when malloc itself is interposed (not under ASan, which owns malloc).
bool malloc_is_counted() noexcept;

// Counts allocations of the current thread between construction and count().
class AllocationScope {
 public:
  AllocationScope() noexcept : start_(thread_allocations()) {}
  std::uint64_t count() const noexcept { return thread_allocations() - start_; }

 private:
  std::uint64_t start_;
};

}  // namespace hapticd::testing
