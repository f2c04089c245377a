// Bounded single-producer single-consumer ring: the one channel from the RT thread to the
// telemetry writer thread (docs/architecture.md, docs/operations.md). A full ring never blocks the
// producer: the record is dropped and counted, and the count is stamped on the next record pushed,
// so the consumer learns exactly where in the stream the loss happened (see pop_run).
//
// Template contract:
//   - T is trivially copyable and default constructible (records are copied by assignment
//     into preallocated slots; nothing is constructed or destroyed on the hot path).
//   - Exactly one thread calls the producer methods (try_push) and exactly one thread calls
//     the consumer methods (pop_many, pop_run, take_trailing_drops) at any time. Handing a
//     role to another thread needs a happens-before edge (e.g. thread join).
//   - dropped(), capacity() and size_approx() may be called from any thread.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <type_traits>

namespace hapticd::telemetry {

template <typename T>
class SpscRing {
  static_assert(std::is_trivially_copyable_v<T>, "SpscRing copies records as plain bytes");
  static_assert(std::is_default_constructible_v<T>, "SpscRing preallocates its slots");

 public:
  // Not RT-safe: allocates and prefaults capacity slots. Throws std::invalid_argument when
  // capacity < 2, std::bad_alloc when the storage cannot be allocated.
  explicit SpscRing(std::size_t capacity) : capacity_(capacity) {
    if (capacity < 2) throw std::invalid_argument("SpscRing capacity must be at least 2");
    slots_.reset(new Slot[capacity]());  // value-initialised: every byte written once
    // Touch every page again through a volatile pointer so the prefault cannot be optimised
    // away; the RT thread must never take a page fault on its first lap around the ring.
    auto* bytes = reinterpret_cast<volatile unsigned char*>(slots_.get());
    const std::size_t total = capacity * sizeof(Slot);
    for (std::size_t off = 0; off < total; off += kPageSize) bytes[off] = bytes[off];
    bytes[total - 1] = bytes[total - 1];
  }

  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  // RT-safe (producer only): wait-free, no allocation, lock or syscall. Copies v into the
  // ring and returns true; when the ring is full, counts one drop and returns false.
  bool try_push(const T& v) noexcept {
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ >= capacity_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ >= capacity_) {
        // Single writer: a plain load+store is enough, no locked read-modify-write needed.
        // Release pairs with take_trailing_drops(), which must see the pushes before it.
        dropped_.store(dropped_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
        return false;
      }
    }
    Slot& slot = slots_[head_index_];
    slot.value = v;
    slot.drops = dropped_.load(std::memory_order_relaxed);
    head_index_ = head_index_ + 1 == capacity_ ? 0 : head_index_ + 1;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  // RT-safe (consumer only): copies up to max of the oldest records into out, in push
  // order, and returns how many. Drops between them are not reported; use pop_run for that.
  std::size_t pop_many(T* out, std::size_t max) noexcept {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t n = std::min<std::uint64_t>(available(tail, max), max);
    for (std::size_t i = 0; i < n; ++i) {
      out[i] = slots_[tail_index_].value;
      drops_seen_ = slots_[tail_index_].drops;
      advance_tail_index();
    }
    if (n > 0) tail_.store(tail + n, std::memory_order_release);
    return n;
  }

  // RT-safe (consumer only): pops up to max of the oldest records that form one run, i.e.
  // with no drop between them, and returns how many. dropped_before is set to the number of
  // records dropped between the previously popped record and the first one returned (0 when
  // nothing is returned). Summed over all runs plus take_trailing_drops() it equals dropped().
  std::size_t pop_run(T* out, std::size_t max, std::uint64_t& dropped_before) noexcept {
    dropped_before = 0;
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    const std::uint64_t avail = std::min<std::uint64_t>(available(tail, max), max);
    if (avail == 0) return 0;
    const std::uint64_t stamp = slots_[tail_index_].drops;
    dropped_before = stamp - drops_seen_;
    std::size_t n = 0;
    while (n < avail && slots_[tail_index_].drops == stamp) {
      out[n++] = slots_[tail_index_].value;
      advance_tail_index();
    }
    drops_seen_ = stamp;
    tail_.store(tail + n, std::memory_order_release);
    return n;
  }

  // RT-safe (consumer only): when the ring is empty, returns the drops not yet reported by
  // pop_run (those after the last record pushed) and marks them reported; returns 0 while
  // records are waiting, since their runs will report them. Safe while the producer runs;
  // called after the producer has stopped it accounts for every remaining drop.
  std::uint64_t take_trailing_drops() noexcept {
    // Order matters: every record pushed before the drop count we read is then visible in
    // head, so an empty ring means all earlier records were popped.
    const std::uint64_t dropped = dropped_.load(std::memory_order_acquire);
    const std::uint64_t head = head_.load(std::memory_order_acquire);
    if (head != tail_.load(std::memory_order_relaxed)) return 0;
    const std::uint64_t trailing = dropped - drops_seen_;
    drops_seen_ = dropped;
    return trailing;
  }

  // RT-safe (any thread): total records dropped because the ring was full.
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_acquire); }

  // RT-safe (any thread): the number of records the ring holds when full.
  std::size_t capacity() const noexcept { return capacity_; }

  // RT-safe (any thread): records waiting to be popped. Called by the producer it is an
  // upper bound (the consumer may pop meanwhile): below capacity(), the next try_push succeeds.
  std::size_t size_approx() const noexcept {
    // tail first: head only grows, so head >= tail even if both move between the loads.
    const std::uint64_t tail = tail_.load(std::memory_order_acquire);
    const std::uint64_t head = head_.load(std::memory_order_acquire);
    return static_cast<std::size_t>(std::min<std::uint64_t>(head - tail, capacity_));
  }

 private:
  static constexpr std::size_t kCacheLine = 64;
  static constexpr std::size_t kPageSize = 4096;

  struct Slot {
    T value{};
    std::uint64_t drops = 0;  // dropped() at the time this record was pushed
  };

  // Records ready for the consumer; reloads the producer's head only when the cached value
  // cannot satisfy the request, to keep the producer's cache line from bouncing.
  std::uint64_t available(std::uint64_t tail, std::size_t want) noexcept {
    if (head_cache_ - tail < want) head_cache_ = head_.load(std::memory_order_acquire);
    return head_cache_ - tail;
  }

  void advance_tail_index() noexcept {
    tail_index_ = tail_index_ + 1 == capacity_ ? 0 : tail_index_ + 1;
  }

  // Read-only after construction, shared by both sides.
  const std::size_t capacity_;
  std::unique_ptr<Slot[]> slots_;

  // Producer side. Positions are monotonic 64-bit counters (they never wrap in practice);
  // the slot index is tracked separately so no division is needed for any capacity.
  alignas(kCacheLine) std::atomic<std::uint64_t> head_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::size_t head_index_ = 0;
  std::uint64_t tail_cache_ = 0;

  // Consumer side.
  alignas(kCacheLine) std::atomic<std::uint64_t> tail_{0};
  std::size_t tail_index_ = 0;
  std::uint64_t head_cache_ = 0;
  std::uint64_t drops_seen_ = 0;  // drops already reported to the consumer
};

}  // namespace hapticd::telemetry
