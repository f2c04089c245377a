#include "alloc_counter.h"

#include <cstdlib>
#include <new>

// Under ASan and TSan the sanitizer owns malloc. GCC says so with __SANITIZE_*__, clang (before
// 17) only through __has_feature.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define HAPTICD_SANITIZER_OWNS_MALLOC 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define HAPTICD_SANITIZER_OWNS_MALLOC 1
#endif
#endif

namespace {
// Zero-initialised TLS needs no dynamic initialisation, so it is safe to touch from malloc.
thread_local std::uint64_t t_allocations = 0;
}  // namespace

namespace hapticd::testing {
std::uint64_t thread_allocations() noexcept { return t_allocations; }
#ifdef HAPTICD_SANITIZER_OWNS_MALLOC
bool malloc_is_counted() noexcept { return false; }
#else
bool malloc_is_counted() noexcept { return true; }
#endif
}  // namespace hapticd::testing

#ifndef HAPTICD_SANITIZER_OWNS_MALLOC
// Where a sanitizer owns malloc, only operator new is counted.
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);

void* malloc(std::size_t n) {
  ++t_allocations;
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  ++t_allocations;
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  ++t_allocations;
  return __libc_realloc(p, n);
}
}
// operator new goes through the interposed malloc above, which does the counting.
#define HAPTICD_COUNT_IN_NEW 0
#else
#define HAPTICD_COUNT_IN_NEW 1
#endif

namespace {
void* counted_new(std::size_t n) {
#if HAPTICD_COUNT_IN_NEW
  ++t_allocations;
#endif
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* counted_new_aligned(std::size_t n, std::align_val_t al) {
  ++t_allocations;  // aligned_alloc is not interposed
  const auto a = static_cast<std::size_t>(al);
  const std::size_t size = (n + a - 1) / a * a;
  if (void* p = std::aligned_alloc(a, size == 0 ? a : size)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t n) { return counted_new(n); }
void* operator new[](std::size_t n) { return counted_new(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return counted_new(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return counted_new(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t n, std::align_val_t al) { return counted_new_aligned(n, al); }
void* operator new[](std::size_t n, std::align_val_t al) { return counted_new_aligned(n, al); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
