// Appends the RT thread's tick records to a binary log (format in log_format.h) from its own
// thread, so disk latency never reaches the RT thread: the only thing they share is the SPSC
// ring. Nothing here is RT-safe.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "base/counters.h"
#include "telemetry/log_format.h"
#include "telemetry/spsc_ring.h"
#include "telemetry/tick_record.h"

namespace hapticd::telemetry {

class LogWriter {
 public:
  // When the writer thread cuts a block. kEveryPoll bounds what a crash can lose to one poll
  // period; kFullBlocks cuts only at max_block_records (and at stop), so the file depends on
  // the records alone and two runs with the same records are byte-identical (freerun).
  enum class Flush { kEveryPoll, kFullBlocks };

  // Creates path, which must not exist yet (keep_previous_log() makes it free; a symlink or
  // anything else planted there meanwhile is refused, never followed or truncated), and writes
  // the file header. Throws std::runtime_error
  // "PATH: cannot open tick log: REASON" when the file cannot be created or the header cannot
  // be written, std::invalid_argument for max_block_records outside 1..kMaxBlockRecords or a
  // configuration text over kMaxConfigBytes. The ring must outlive the writer; the writer is
  // its only consumer.
  LogWriter(const std::string& path, const LogHeader& header, SpscRing<TickRecord>& ring,
            std::size_t max_block_records = 512,
            std::chrono::milliseconds poll = std::chrono::milliseconds(5),
            Flush flush = Flush::kEveryPoll);
  ~LogWriter();  // stop()

  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  // Starts the writer thread, which every `poll` drains the ring into blocks of at most
  // max_block_records records and appends them with write(2). A second call does nothing;
  // calling it after stop() throws std::logic_error.
  void start();

  // Call after the producer has stopped pushing. Joins the thread, drains what is left,
  // writes a loss marker for drops not yet in the log, then fdatasync and close. Never
  // throws; failures are counted in io_errors(). Idempotent. start() and stop() belong to
  // one controlling thread.
  void stop();

  // How big the log may grow (telemetry.max_segment_mb, telemetry.max_total_mb); 0 = no limit.
  struct Rotation {
    // Before a block would take the segment past this, the writer closes it and goes on in a
    // new one (log_path.h: PATH.part2, PATH.part3, ...): a complete log with its own header
    // (the configuration in force, the run's start time) whose ticks continue the last one's.
    std::uint64_t max_segment_bytes = 0;
    // Retention cap of the log's whole family, older runs' sets included: at set_rotation()
    // and after every roll the oldest files go until the others plus max_segment_bytes fit
    // (log_retention.h). The segment being written is never deleted.
    std::uint64_t max_total_bytes = 0;
    // Told one sentence per roll and per deletion, from the writer thread (and from
    // set_rotation's caller). Not RT: it may log. What it throws is ignored.
    std::function<void(const std::string&)> on_event;
  };
  // Before start(), from the controlling thread. Applies the retention cap once at once.
  void set_rotation(Rotation rotation);
  // Segments begun so far (1 + rolls), files deleted by retention and the bytes they held.
  std::uint32_t segments() const noexcept;
  std::uint64_t files_deleted() const noexcept;
  std::uint64_t bytes_deleted() const noexcept;

  // Any thread. The configuration a live reload is about to swap in (or a re-arming starts
  // with): written as a config block right after the block holding the marker record
  // (TickRecord::marker == kMarkerReloadAccepted or kMarkerRearmed), so the log says which law
  // governs from which tick. Queue it before the RT thread can take the new law;
  // withdraw_config_change() takes it back if the reload does not happen after all.
  void queue_config_change(std::string config_text);
  void withdraw_config_change();

  // Before stop(), from the controlling thread: what stop() writes as the log's counters block
  // (log_format.h), called once after the last record, when the producer has stopped. The
  // run's counter registry, so a log carries the driver's health as the summary does.
  void set_counters(std::function<std::vector<base::CounterReading>()> counters);

  // Records that are in the log (their block was written completely).
  std::uint64_t records_written() const noexcept;
  // Records the RT ring dropped because it was full, as reported to the writer so far; after
  // stop() this equals ring.dropped(). They are marked in the log (dropped_before).
  std::uint64_t records_dropped() const noexcept;
  // Records that left the ring but never reached the disk (their block failed to write:
  // disk full, file-size limit). Marked in the log like drops when a later write succeeds.
  std::uint64_t records_lost() const noexcept;
  // Failed or short writes, failed fdatasync/close. Never thrown from the thread.
  std::uint64_t io_errors() const noexcept;
  // The first I/O error as "PATH: what failed: strerror" (later ones are usually its
  // consequences), "" if none.
  std::string last_error() const;
  const std::string& path() const noexcept;

 private:
  void run();
  // final: also write the last partial block (kFullBlocks holds it back otherwise).
  void drain(bool final);
  void append_block(std::span<const TickRecord> records, std::uint64_t first_tick,
                    std::uint64_t dropped_before);
  // Appends records [0, n), cutting after each accepted-reload marker for its config block.
  void append_records(std::size_t n, std::uint64_t dropped_before);
  void append_config_block(std::uint64_t first_tick);
  void append_counters_block() noexcept;
  bool write_bytes(std::span<const std::byte> bytes);
  void note_error(const char* what, int err);
  void note_error(const std::string& message);  // the whole message, for last_error()
  // Rotation, on the thread that drains.
  void roll(std::uint64_t first_tick);
  void close_segment() noexcept;
  void retain() noexcept;
  void tell(const std::string& sentence) noexcept;

  std::string path_;
  LogHeader header_;   // each segment's header; config_text follows the reloads
  Rotation rotation_;  // set before start()
  std::function<std::vector<base::CounterReading>()> counters_;  // set before stop()
  std::string segment_;  // the file being written: path_, then path_.part2, ...
  std::uint32_t segment_index_ = 1;
  off_t header_bytes_ = 0;  // of the segment being written
  SpscRing<TickRecord>& ring_;
  std::chrono::milliseconds poll_;
  Flush flush_;
  int fd_ = -1;

  // Touched only by the thread that drains (the writer thread, then stop() after the join).
  std::vector<TickRecord> staging_;     // preallocated: max_block_records records
  std::vector<std::byte> block_bytes_;  // preallocated: one encoded block
  off_t good_end_ = 0;                  // file offset just after the last complete block
  bool tail_dirty_ = false;             // a failed write may have left bytes after good_end_
  std::uint64_t pending_loss_ = 0;      // records lost but not yet marked in the log
  std::uint64_t next_tick_ = 0;         // tick after the last record popped

  std::atomic<std::uint64_t> records_written_{0};
  std::atomic<std::uint64_t> ring_dropped_{0};
  std::atomic<std::uint64_t> io_lost_{0};
  std::atomic<std::uint64_t> io_errors_{0};
  std::atomic<std::uint32_t> segments_{1};
  std::atomic<std::uint64_t> files_deleted_{0};
  std::atomic<std::uint64_t> bytes_deleted_{0};
  mutable std::mutex error_mutex_;
  std::string first_error_;

  std::mutex config_mutex_;
  std::deque<std::string> config_changes_;  // guarded by config_mutex_

  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool stop_requested_ = false;  // guarded by wake_mutex_
  std::thread thread_;
  bool started_ = false;
  bool stopped_ = false;
};

// Writes a complete log of records to a new file (path must not exist) in blocks of at most
// max_block_records, then fdatasync.
// Throws std::runtime_error "PATH: cannot open tick log: REASON" or "PATH: cannot write tick
// log: REASON", std::invalid_argument as LogWriter does.
void write_log_file(const std::string& path, const LogHeader& header,
                    std::span<const TickRecord> records, std::size_t max_block_records = 512);

}  // namespace hapticd::telemetry
