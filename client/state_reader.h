// A client's reader of the state block (state_layout.h): maps the descriptor the daemon passed
// read-only and reads samples without a system call. Any thread; one reader per thread (next()
// keeps its place).
#pragma once

#include <cstdint>

#include "state_layout.h"

namespace hapticd::client {

class StateReader {
 public:
  // Takes ownership of `fd` (closed by the destructor, or here on failure). Throws ClientError
  // (connection.h) naming what is wrong: not a state block, a layout this reader does not know.
  explicit StateReader(int fd);
  ~StateReader();
  StateReader(StateReader&& other) noexcept;
  StateReader& operator=(StateReader&&) = delete;
  StateReader(const StateReader&) = delete;
  StateReader& operator=(const StateReader&) = delete;

  enum class Read { kOk, kMissed, kNotYet };
  // Sample n: kMissed when the loop has written over it already, kNotYet when it is not whole
  // yet (not written, or being written).
  Read read(std::uint64_t n, StateSample& out) const noexcept;
  // The newest whole sample; false when there is none yet.
  bool latest(StateSample& out) const noexcept;
  // The sample after the one next() returned last (the first: the first written after the
  // first call), every tick in order; false when none is new yet. Samples overwritten before it
  // got to them are counted (missed).
  bool next(StateSample& out) noexcept;

  std::uint64_t head() const noexcept;  // samples written so far
  std::uint64_t missed() const noexcept { return missed_; }
  std::uint32_t slots() const noexcept { return header_->slots; }
  std::uint64_t sample_period_ns() const noexcept { return header_->sample_period_ns; }
  std::uint32_t joints() const noexcept { return header_->joints; }
  std::uint32_t axes() const noexcept { return header_->axes; }

 private:
  const StateSlot& slot(std::uint64_t n) const noexcept;

  int fd_ = -1;
  void* map_ = nullptr;
  std::size_t bytes_ = 0;
  const StateHeader* header_ = nullptr;
  std::uint64_t next_ = 0;
  bool started_ = false;
  std::uint64_t missed_ = 0;
};

}  // namespace hapticd::client
