#include "telemetry/log_writer.h"

#include <fcntl.h>
#include <pthread.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <stdexcept>

#include "base/errno_text.h"
#include "telemetry/log_path.h"
#include "telemetry/log_retention.h"

namespace hapticd::telemetry {
namespace {

void check_block_records(std::size_t max_block_records) {
  if (max_block_records == 0 || max_block_records > kMaxBlockRecords) {
    throw std::invalid_argument("tick log: max_block_records must be in 1.." +
                                std::to_string(kMaxBlockRecords));
  }
}

int open_log(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error(path + ": cannot open tick log: " + base::errno_text(errno));
  return fd;
}

// Writes all n bytes, resuming after short writes. Returns 0 or the errno that stopped it.
int write_all(int fd, const std::byte* p, std::size_t n) noexcept {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    if (w == 0) return EIO;  // no progress and no error: do not spin
    p += w;
    n -= static_cast<std::size_t>(w);
  }
  return 0;
}

}  // namespace

LogWriter::LogWriter(const std::string& path, const LogHeader& header, SpscRing<TickRecord>& ring,
                     std::size_t max_block_records, std::chrono::milliseconds poll, Flush flush)
    : path_(path), header_(header), segment_(path), ring_(ring), poll_(poll), flush_(flush) {
  check_block_records(max_block_records);
  if (poll.count() <= 0) throw std::invalid_argument("tick log: poll period must be positive");
  const std::vector<std::byte> head = encode_file_header(header);  // validates before opening
  staging_.resize(max_block_records);
  block_bytes_.resize(block_size(max_block_records));
  fd_ = open_log(path_);
  if (const int err = write_all(fd_, head.data(), head.size()); err != 0) {
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error(
        path_ + ": cannot open tick log: writing the header failed: " + base::errno_text(err));
  }
  good_end_ = static_cast<off_t>(head.size());
  header_bytes_ = good_end_;
}

LogWriter::~LogWriter() { stop(); }

void LogWriter::start() {
  if (stopped_) throw std::logic_error(path_ + ": tick log writer started after stop()");
  if (started_) return;
  thread_ = std::thread([this] { run(); });
  // Visible in top -H / ps -L; best effort.
  pthread_setname_np(thread_.native_handle(), "hapticd-log");
  started_ = true;
}

void LogWriter::stop() {
  if (stopped_) return;
  stopped_ = true;
  if (thread_.joinable()) {
    {
      std::lock_guard lock(wake_mutex_);
      stop_requested_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  drain(/*final=*/true);
  // Drops after the last record pushed are not stamped on any record: mark them here.
  const std::uint64_t trailing = ring_.take_trailing_drops();
  if (trailing + pending_loss_ > 0) append_block({}, next_tick_, trailing);
  append_counters_block();
  close_segment();
}

void LogWriter::set_counters(std::function<std::vector<base::CounterReading>()> counters) {
  counters_ = std::move(counters);
}

void LogWriter::append_counters_block() noexcept {
  if (!counters_) return;
  try {
    std::string text;
    for (const base::CounterReading& c : counters_()) {
      text += c.source + " " + c.name + " " + std::string(base::to_string(c.kind)) + " " +
              std::to_string(c.value) + "\n";
    }
    write_bytes(encode_counters_block(next_tick_, text));
  } catch (const std::exception& e) {
    note_error(std::string("counters block not written: ") + e.what());
  }
}

void LogWriter::close_segment() noexcept {
  // A failed write may have left a partial block after the last good one.
  if (tail_dirty_ && ::ftruncate(fd_, good_end_) != 0) note_error("truncate failed", errno);
  if (::fdatasync(fd_) != 0) note_error("fdatasync failed", errno);
  if (::close(fd_) != 0) note_error("close failed", errno);
  fd_ = -1;
}

std::uint64_t LogWriter::records_written() const noexcept {
  return records_written_.load(std::memory_order_relaxed);
}
std::uint64_t LogWriter::records_dropped() const noexcept {
  return ring_dropped_.load(std::memory_order_relaxed);
}
std::uint64_t LogWriter::records_lost() const noexcept {
  return io_lost_.load(std::memory_order_relaxed);
}
std::uint64_t LogWriter::io_errors() const noexcept {
  return io_errors_.load(std::memory_order_acquire);
}
std::string LogWriter::last_error() const {
  std::lock_guard lock(error_mutex_);
  return first_error_;
}
const std::string& LogWriter::path() const noexcept { return path_; }

void LogWriter::run() {
  std::unique_lock lock(wake_mutex_);
  while (!stop_requested_) {
    lock.unlock();
    drain(/*final=*/false);
    lock.lock();
    wake_.wait_for(lock, poll_, [this] { return stop_requested_; });
  }
}

void LogWriter::drain(bool final) {
  // kFullBlocks cuts every block at the same count, which a ring smaller than a block must
  // be able to reach.
  const std::size_t full = std::min(staging_.size(), ring_.capacity());
  const std::size_t want = flush_ == Flush::kFullBlocks ? full : staging_.size();
  std::uint64_t dropped_before = 0;
  for (;;) {
    if (!final && flush_ == Flush::kFullBlocks && ring_.size_approx() < full) return;
    const std::size_t n = ring_.pop_run(staging_.data(), want, dropped_before);
    if (n == 0) return;
    append_records(n, dropped_before);
    next_tick_ = staging_[n - 1].tick + 1;
  }
}

void LogWriter::queue_config_change(std::string config_text) {
  std::lock_guard lock(config_mutex_);
  config_changes_.push_back(std::move(config_text));
}

void LogWriter::withdraw_config_change() {
  std::lock_guard lock(config_mutex_);
  if (!config_changes_.empty()) config_changes_.pop_back();
}

void LogWriter::append_records(std::size_t n, std::uint64_t dropped_before) {
  std::size_t from = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t m = staging_[i].marker;
    if (m != kMarkerReloadAccepted && m != kMarkerRearmed) continue;
    append_block(std::span(staging_.data() + from, i + 1 - from), staging_[from].tick,
                 from == 0 ? dropped_before : 0);
    append_config_block(staging_[i].tick);
    from = i + 1;
  }
  if (from < n) {
    append_block(std::span(staging_.data() + from, n - from), staging_[from].tick,
                 from == 0 ? dropped_before : 0);
  }
}

void LogWriter::append_config_block(std::uint64_t first_tick) {
  std::string text;
  {
    std::lock_guard lock(config_mutex_);
    if (config_changes_.empty()) return;  // nothing queued: the marker alone says a reload happened
    text = std::move(config_changes_.front());
    config_changes_.pop_front();
  }
  try {
    write_bytes(encode_config_block(first_tick, text));
  } catch (const std::exception&) {
    note_error("config block too large", EFBIG);
  }
  // The next segments' headers carry the configuration in force when they begin.
  header_.config_text = std::move(text);
}

bool LogWriter::write_bytes(std::span<const std::byte> bytes) {
  const int err = write_all(fd_, bytes.data(), bytes.size());
  if (err == 0) {
    good_end_ += static_cast<off_t>(bytes.size());
    return true;
  }
  note_error("write failed", err);
  tail_dirty_ = true;
  ::lseek(fd_, good_end_, SEEK_SET);  // the next block overwrites the partial one
  return false;
}

void LogWriter::append_block(std::span<const TickRecord> records, std::uint64_t first_tick,
                             std::uint64_t dropped_before) {
  // A segment holds at least one block; the next one would pass the cap: roll first.
  if (rotation_.max_segment_bytes != 0 && good_end_ > header_bytes_ &&
      static_cast<std::uint64_t>(good_end_) + block_size(records.size()) >
          rotation_.max_segment_bytes) {
    roll(first_tick);
  }
  // The ring's loss is known now, whether or not its marker reaches the disk.
  ring_dropped_.fetch_add(dropped_before, std::memory_order_relaxed);
  // Records that earlier failed to reach the disk are marked with the next block that does.
  const std::uint64_t marker = pending_loss_ + dropped_before;
  const std::size_t size = encode_block(block_bytes_, first_tick, marker, records);
  const int err = write_all(fd_, block_bytes_.data(), size);
  if (err == 0) {
    good_end_ += static_cast<off_t>(size);
    pending_loss_ = 0;
    records_written_.fetch_add(records.size(), std::memory_order_relaxed);
    return;
  }
  note_error("write failed", err);
  io_lost_.fetch_add(records.size(), std::memory_order_relaxed);
  pending_loss_ = marker + records.size();
  tail_dirty_ = true;
  // Rewind so the next block overwrites the partial one and the log stays readable past it
  // (fails harmlessly on a non-seekable file).
  ::lseek(fd_, good_end_, SEEK_SET);
}

void LogWriter::note_error(const char* what, int err) {
  {
    std::lock_guard lock(error_mutex_);
    if (first_error_.empty()) {
      try {
        first_error_ = segment_ + ": " + what + ": " + base::errno_text(err);
      } catch (...) {
        // Out of memory while formatting: the count below still records the error.
      }
    }
  }
  io_errors_.fetch_add(1, std::memory_order_release);
}

void LogWriter::note_error(const std::string& message) {
  {
    std::lock_guard lock(error_mutex_);
    if (first_error_.empty()) first_error_ = message;
  }
  io_errors_.fetch_add(1, std::memory_order_release);
}

void LogWriter::set_rotation(Rotation rotation) {
  rotation_ = std::move(rotation);
  retain();
}

std::uint32_t LogWriter::segments() const noexcept {
  return segments_.load(std::memory_order_relaxed);
}
std::uint64_t LogWriter::files_deleted() const noexcept {
  return files_deleted_.load(std::memory_order_relaxed);
}
std::uint64_t LogWriter::bytes_deleted() const noexcept {
  return bytes_deleted_.load(std::memory_order_relaxed);
}

void LogWriter::tell(const std::string& sentence) noexcept {
  if (!rotation_.on_event) return;
  try {
    rotation_.on_event(sentence);
  } catch (...) {
    // A sink that fails must not take the log down with it.
  }
}

// The next segment is opened and given its header before the current one is closed: when it
// cannot be (a full disk, a name taken), the writer stays in the current segment, past the
// cap, and tries again at the next block.
void LogWriter::roll(std::uint64_t first_tick) {
  const std::string next = segment_path(path_, segment_index_ + 1);
  std::vector<std::byte> head;
  try {
    head = encode_file_header(header_);
  } catch (const std::exception&) {
    note_error("cannot encode the next segment's header", EINVAL);
    return;
  }
  const int fd = ::open(next.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  const int err = fd < 0 ? errno : write_all(fd, head.data(), head.size());
  if (err != 0) {
    if (fd >= 0) {
      ::close(fd);
      ::unlink(next.c_str());
    }
    note_error("cannot start the next segment", err);
    retain();  // what retention frees may let the next attempt succeed
    return;
  }
  close_segment();
  fd_ = fd;
  segment_ = next;
  ++segment_index_;
  good_end_ = header_bytes_ = static_cast<off_t>(head.size());
  tail_dirty_ = false;
  segments_.store(segment_index_, std::memory_order_relaxed);
  tell("tick log: segment " + std::to_string(segment_index_) + " is " + next + " (from tick " +
       std::to_string(first_tick) + ")");
  retain();
}

void LogWriter::retain() noexcept {
  if (rotation_.max_total_bytes == 0) return;
  try {
    const RetentionResult r =
        enforce_retention(path_, segment_, rotation_.max_total_bytes, rotation_.max_segment_bytes);
    for (const std::string& e : r.errors) {
      tell("tick log: retention: " + e);
      note_error("retention: " + e);
    }
    if (r.deleted.empty()) return;
    files_deleted_.fetch_add(r.deleted.size(), std::memory_order_relaxed);
    bytes_deleted_.fetch_add(r.bytes, std::memory_order_relaxed);
    std::string names;
    for (const std::string& d : r.deleted) names += (names.empty() ? "" : ", ") + d;
    tell("tick log: retention deleted " + std::to_string(r.deleted.size()) + " file(s), " +
         std::to_string(r.bytes) + " bytes, to keep the logs under " +
         std::to_string(rotation_.max_total_bytes) + " bytes: " + names);
  } catch (const std::exception& e) {
    try {
      tell(std::string("tick log: retention: ") + e.what());
      note_error(std::string("retention: ") + e.what());
    } catch (...) {
      io_errors_.fetch_add(1, std::memory_order_release);  // out of memory: still counted
    }
  }
}

void write_log_file(const std::string& path, const LogHeader& header,
                    std::span<const TickRecord> records, std::size_t max_block_records) {
  check_block_records(max_block_records);
  const std::vector<std::byte> head = encode_file_header(header);
  std::vector<std::byte> block(block_size(std::min(max_block_records, records.size())));
  const int fd = open_log(path);
  int err = write_all(fd, head.data(), head.size());
  for (std::size_t at = 0; err == 0 && at < records.size(); at += max_block_records) {
    const auto chunk = records.subspan(at, std::min(max_block_records, records.size() - at));
    const std::size_t size = encode_block(block, chunk.front().tick, 0, chunk);
    err = write_all(fd, block.data(), size);
  }
  if (err == 0 && ::fdatasync(fd) != 0) err = errno;
  if (::close(fd) != 0 && err == 0) err = errno;
  if (err != 0)
    throw std::runtime_error(path + ": cannot write tick log: " + base::errno_text(err));
}

}  // namespace hapticd::telemetry
