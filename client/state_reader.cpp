#include "state_reader.h"

#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

#include "connection.h"

namespace hapticd::client {
namespace {

ClientError refused(int fd, const std::string& why) {
  close(fd);
  return ClientError("state block: " + why);
}

}  // namespace

StateReader::StateReader(int fd) : fd_(fd) {
  struct stat st {};
  if (fstat(fd, &st) != 0) throw refused(fd, std::string("fstat: ") + std::strerror(errno));
  if (st.st_size < static_cast<off_t>(kStateHeaderBytes)) {
    throw refused(fd, "shorter than its header (" + std::to_string(st.st_size) + " bytes)");
  }
  bytes_ = static_cast<std::size_t>(st.st_size);
  map_ = mmap(nullptr, bytes_, PROT_READ, MAP_SHARED, fd, 0);
  if (map_ == MAP_FAILED) throw refused(fd, std::string("mmap: ") + std::strerror(errno));
  header_ = static_cast<const StateHeader*>(map_);
  std::string why;
  if (std::memcmp(header_->magic, kStateMagic, sizeof kStateMagic) != 0) {
    why = "not a hapticd state block (its magic is not HAPTSTAT)";
  } else if (header_->layout != kStateLayout || header_->header_bytes != kStateHeaderBytes ||
             header_->slot_bytes != kStateSlotBytes) {
    why = "layout " + std::to_string(header_->layout) + " (this reader knows layout " +
          std::to_string(kStateLayout) + ")";
  } else if (header_->slots == 0 || (header_->slots & (header_->slots - 1)) != 0 ||
             bytes_ < kStateHeaderBytes + std::size_t{header_->slots} * kStateSlotBytes) {
    why = "its " + std::to_string(header_->slots) + " slots do not fit its " +
          std::to_string(bytes_) + " bytes";
  }
  if (!why.empty()) {
    munmap(map_, bytes_);
    throw refused(fd, why);
  }
}

StateReader::~StateReader() {
  if (map_ != nullptr) munmap(map_, bytes_);
  if (fd_ >= 0) close(fd_);
}

StateReader::StateReader(StateReader&& o) noexcept
    : fd_(std::exchange(o.fd_, -1)),
      map_(std::exchange(o.map_, nullptr)),
      bytes_(o.bytes_),
      header_(o.header_),
      next_(o.next_),
      started_(o.started_),
      missed_(o.missed_) {}

const StateSlot& StateReader::slot(std::uint64_t n) const noexcept {
  const auto* base = static_cast<const unsigned char*>(map_) + kStateHeaderBytes;
  return *reinterpret_cast<const StateSlot*>(base + (n & (header_->slots - 1)) * kStateSlotBytes);
}

std::uint64_t StateReader::head() const noexcept {
  return header_->head.load(std::memory_order_acquire);
}

StateReader::Read StateReader::read(std::uint64_t n, StateSample& out) const noexcept {
  const StateSlot& s = slot(n);
  const std::uint64_t whole = 2 * n + 2;
  const std::uint64_t before = s.sequence.load(std::memory_order_acquire);
  if (before < whole) return Read::kNotYet;
  if (before > whole) return Read::kMissed;
  std::uint64_t words[kStateWords];
  // Each word an acquire: the second look at the sequence comes after them, and sees the odd
  // sequence of any write whose word it read (the writer stores each word as a release).
  for (std::size_t i = 0; i < kStateWords; ++i) {
    words[i] = s.words[i].load(std::memory_order_acquire);
  }
  if (s.sequence.load(std::memory_order_relaxed) != whole) return Read::kMissed;
  std::memcpy(&out, words, sizeof out);
  return Read::kOk;
}

bool StateReader::latest(StateSample& out) const noexcept {
  const std::uint64_t h = head();
  // The newest is whole once head counts it; one being written over meanwhile is lost, the
  // one after it is newer.
  for (std::uint64_t n = h; n > 0 && n + header_->slots > h; --n) {
    if (read(n - 1, out) == Read::kOk) return true;
  }
  return false;
}

bool StateReader::next(StateSample& out) noexcept {
  const std::uint64_t h = head();
  if (!started_) {
    started_ = true;
    next_ = h;
  }
  while (next_ < h) {
    const Read r = read(next_, out);
    if (r == Read::kNotYet) return false;
    if (r == Read::kOk) {
      ++next_;
      return true;
    }
    // Written over: everything older than the oldest slot still held is gone (that one too, if
    // the loop is writing over it now: the next read says so).
    const std::uint64_t oldest = h > header_->slots ? h - header_->slots : 0;
    const std::uint64_t skip_to = next_ + 1 > oldest ? next_ + 1 : oldest;
    missed_ += skip_to - next_;
    next_ = skip_to;
  }
  return false;
}

}  // namespace hapticd::client
