#include "service/cli/event_log.h"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>

namespace hapticd::service::cli {
namespace {

// Whether standard error is a stream to the journal (a service's, as systemd sets
// $JOURNAL_STREAM to its device and inode): journald then reads a "<N>" prefix as the line's
// syslog priority (sd-daemon(3)), so `journalctl -p warning` finds the warnings and errors.
bool stderr_is_journal() {
  const char* stream = std::getenv("JOURNAL_STREAM");
  struct stat st {};
  if (stream == nullptr || fstat(STDERR_FILENO, &st) != 0) return false;
  unsigned long long dev = 0, ino = 0;
  return std::sscanf(stream, "%llu:%llu", &dev, &ino) == 2 && dev == st.st_dev && ino == st.st_ino;
}

// The "<N>" of an event's level; the journal has its own time stamps and unit name.
class JournalPriority : public spdlog::custom_flag_formatter {
 public:
  static const char* priority(spdlog::level::level_enum level) {
    switch (level) {
      case spdlog::level::critical:
        return SD_CRIT;
      case spdlog::level::err:
        return SD_ERR;
      case spdlog::level::warn:
        return SD_WARNING;
      case spdlog::level::info:
        return SD_INFO;
      default:
        return SD_DEBUG;  // trace, debug
    }
  }
  void format(const spdlog::details::log_msg& msg, const std::tm&,
              spdlog::memory_buf_t& dest) override {
    const char* p = priority(msg.level);
    dest.append(p, p + std::strlen(p));
  }
  std::unique_ptr<custom_flag_formatter> clone() const override {
    return std::make_unique<JournalPriority>();
  }
};

}  // namespace

const char* set_up_event_log() {
  spdlog::set_default_logger(spdlog::stderr_color_mt("hapticd"));
  if (!stderr_is_journal()) return "";
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  formatter->add_flag<JournalPriority>('*').set_pattern("%*[%l] %v");
  spdlog::set_formatter(std::move(formatter));
  return SD_ERR;
}

}  // namespace hapticd::service::cli
