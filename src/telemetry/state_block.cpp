#include "telemetry/state_block.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "base/errno_text.h"

namespace hapticd::telemetry {
namespace {

std::runtime_error failed(const char* call) {
  return std::runtime_error(std::string("state block: ") + call + ": " + base::errno_text(errno));
}

}  // namespace

StateBlock::StateBlock(std::uint32_t slots, std::int64_t sample_period_ns, std::uint32_t joints,
                       std::uint32_t axes) {
  if (slots == 0 || (slots & (slots - 1)) != 0) {
    throw std::invalid_argument("state block: " + std::to_string(slots) +
                                " slots is no power of two");
  }
  bytes_ = client::kStateHeaderBytes + std::size_t{slots} * client::kStateSlotBytes;
  fd_ = memfd_create("hapticd-state", MFD_CLOEXEC | MFD_ALLOW_SEALING);
  if (fd_ < 0) throw failed("memfd_create");
  try {
    if (ftruncate(fd_, static_cast<off_t>(bytes_)) != 0) throw failed("ftruncate");
    map_ = mmap(nullptr, bytes_, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, 0);
    if (map_ == MAP_FAILED) {
      map_ = nullptr;
      throw failed("mmap");
    }
    // Readers map it read-only and can neither resize it under the loop nor write into it.
    if (fcntl(fd_, F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_FUTURE_WRITE | F_SEAL_SEAL) !=
        0) {
      throw failed("F_ADD_SEALS");
    }
  } catch (...) {
    if (map_ != nullptr) munmap(map_, bytes_);
    close(fd_);
    throw;
  }
  std::memset(map_, 0, bytes_);  // every page touched now: no fault on the RT thread
  header_ = new (map_) client::StateHeader{};
  std::memcpy(header_->magic, client::kStateMagic, sizeof client::kStateMagic);
  header_->layout = client::kStateLayout;
  header_->header_bytes = client::kStateHeaderBytes;
  header_->slot_bytes = client::kStateSlotBytes;
  header_->slots = slots;
  header_->sample_period_ns = static_cast<std::uint64_t>(sample_period_ns);
  header_->joints = joints;
  header_->axes = axes;
  auto* first = static_cast<unsigned char*>(map_) + client::kStateHeaderBytes;
  slots_ = new (first) client::StateSlot[slots]{};
}

StateBlock::~StateBlock() {
  if (map_ != nullptr) munmap(map_, bytes_);
  if (fd_ >= 0) close(fd_);
}

void StateBlock::publish(const client::StateSample& s) noexcept {
  const std::uint64_t n = header_->head.load(std::memory_order_relaxed);
  client::StateSlot& slot = slots_[n & (header_->slots - 1)];
  std::uint64_t words[client::kStateWords];
  std::memcpy(words, &s, sizeof words);
  // Each word a release: a reader that sees any of them sees the odd sequence before it (no
  // fence: ThreadSanitizer does not follow fences; on x86 and ARMv8 these are plain stores).
  slot.sequence.store(2 * n + 1, std::memory_order_relaxed);
  for (std::size_t i = 0; i < client::kStateWords; ++i) {
    slot.words[i].store(words[i], std::memory_order_release);
  }
  slot.sequence.store(2 * n + 2, std::memory_order_release);
  header_->head.store(n + 1, std::memory_order_release);
}

}  // namespace hapticd::telemetry
