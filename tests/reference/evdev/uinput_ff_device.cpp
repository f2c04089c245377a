#include "uinput_ff_device.h"
#include "reference_clock.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <stdexcept>

namespace hapticd::reference {
namespace {

void must(int rc, const char* what) {
  if (rc < 0)
    throw std::runtime_error(std::string("uinput: ") + what + ": " + std::strerror(errno));
}

}  // namespace

UinputFfDevice::UinputFfDevice(const UinputFfOptions& o)
    : o_(o), x_(o.start), effects_(static_cast<std::size_t>(o.effects)) {
  fd_.reset(::open("/dev/uinput", O_RDWR | O_NONBLOCK | O_CLOEXEC));
  must(fd_.get(), "open /dev/uinput");
  const int fd = fd_.get();
  must(ioctl(fd, UI_SET_EVBIT, EV_ABS), "UI_SET_EVBIT EV_ABS");
  must(ioctl(fd, UI_SET_ABSBIT, ABS_X), "UI_SET_ABSBIT");
  must(ioctl(fd, UI_SET_EVBIT, EV_FF), "UI_SET_EVBIT EV_FF");
  for (int bit : {FF_CONSTANT, FF_GAIN, FF_AUTOCENTER})
    must(ioctl(fd, UI_SET_FFBIT, bit), "UI_SET_FFBIT");
  uinput_abs_setup abs{};
  abs.code = ABS_X;
  abs.absinfo.minimum = o.axis_min;
  abs.absinfo.maximum = o.axis_max;
  must(ioctl(fd, UI_ABS_SETUP, &abs), "UI_ABS_SETUP");
  uinput_setup setup{};
  setup.id = {BUS_VIRTUAL, o.vendor, o.product, 1};
  std::strncpy(setup.name, o.name.c_str(), UINPUT_MAX_NAME_SIZE - 1);
  setup.ff_effects_max = static_cast<__u32>(o.effects);
  must(ioctl(fd, UI_DEV_SETUP, &setup), "UI_DEV_SETUP");
  must(ioctl(fd, UI_DEV_CREATE), "UI_DEV_CREATE");
  char sysname[64] = {};
  must(ioctl(fd, UI_GET_SYSNAME(sizeof sysname - 1), sysname), "UI_GET_SYSNAME");
  namespace fs = std::filesystem;
  for (const auto& e : fs::directory_iterator(fs::path("/sys/class/input") / sysname)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("event", 0) == 0) event_path_ = "/dev/input/" + n;
  }
  if (event_path_.empty())
    throw std::runtime_error("uinput: no event node for " + std::string(sysname));
  for (int i = 0; i < 200 && !fs::exists(event_path_); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));  // devtmpfs makes the node
  }
  emit(EV_ABS, ABS_X, 0);  // the first report, so the kernel's value is the axis'
  thread_ = std::thread([this] { run(); });
}

UinputFfDevice::~UinputFfDevice() { unplug(); }

void UinputFfDevice::unplug() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  if (!gone_.exchange(true)) ioctl(fd_.get(), UI_DEV_DESTROY);
  force_.store(0.0);
  playing_.store(false);
}

double UinputFfDevice::position() const {
  const std::lock_guard lock(m_);
  return x_;
}

std::vector<Upload> UinputFfDevice::uploads() const {
  const std::lock_guard lock(m_);
  return uploads_;
}

std::vector<Stop> UinputFfDevice::stops() const {
  const std::lock_guard lock(m_);
  return stops_;
}

void UinputFfDevice::emit(int type, int code, int value) {
  if (type == EV_ABS) {
    const double span = o_.position_max - o_.position_min;
    double x = 0.0;
    {
      const std::lock_guard lock(m_);
      x = x_;
    }
    value = static_cast<int>(
        std::lround(o_.axis_min + (x - o_.position_min) / span * (o_.axis_max - o_.axis_min)));
    if (value == reported_) return;  // the kernel would drop it: nothing changed
    reported_ = value;
  }
  input_event ev[2]{};
  ev[0].type = static_cast<__u16>(type);
  ev[0].code = static_cast<__u16>(code);
  ev[0].value = value;
  ev[1].type = EV_SYN;
  ev[1].code = SYN_REPORT;
  [[maybe_unused]] const ssize_t n = ::write(fd_.get(), ev, sizeof ev);
}

// <linux/uinput.h>, "To implement upload_effect()": 3. UI_BEGIN_FF_UPLOAD fills in the struct,
// 4. "Perform the effect upload, and place a return code back", 5. UI_END_FF_UPLOAD; and "The
// callback blocks until this return code is sent". Step 3 at once, 4 and 5 after upload_latency.
void UinputFfDevice::upload_request(int request) {
  uinput_ff_upload up{};
  up.request_id = static_cast<__u32>(request);
  if (ioctl(fd_.get(), UI_BEGIN_FF_UPLOAD, &up) < 0) return;
  pending_ = up;
  pending_due_ = std::chrono::steady_clock::now() + o_.upload_latency;
  answering_.store(true);
  if (o_.upload_latency.count() == 0) finish_upload();
}

void UinputFfDevice::finish_upload() {
  uinput_ff_upload& up = *pending_;
  const int id = up.effect.id;
  if (up.effect.type != FF_CONSTANT || id < 0 || id >= o_.effects) {
    up.retval = -EINVAL;
  } else {
    const std::lock_guard lock(m_);
    Effect& e = effects_[static_cast<std::size_t>(id)];
    e.used = true;
    e.level = up.effect.u.constant.level;
    e.direction = up.effect.direction;
    uploads_.push_back({now_ns(), id, e.level});
  }
  ioctl(fd_.get(), UI_END_FF_UPLOAD, &up);
  pending_.reset();
  answering_.store(false);
}

// Until the next step of the axis, or the pending upload's answer if that comes first.
int UinputFfDevice::poll_timeout_ms(std::chrono::steady_clock::time_point next) const {
  const auto until = pending_ ? std::min(next, pending_due_) : next;
  const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(
      until - std::chrono::steady_clock::now());
  return static_cast<int>(std::max<std::int64_t>(0, wait.count()));
}

void UinputFfDevice::erase_request(int request) {
  uinput_ff_erase er{};
  er.request_id = static_cast<__u32>(request);
  if (ioctl(fd_.get(), UI_BEGIN_FF_ERASE, &er) < 0) return;
  if (er.effect_id < effects_.size()) {
    const std::lock_guard lock(m_);
    effects_[er.effect_id] = {};
  }
  erases_.fetch_add(1);
  ioctl(fd_.get(), UI_END_FF_ERASE, &er);
}

// Everything the kernel passed to the device: upload and erase requests, and the EV_FF
// events written to its node (play or stop an effect, the gain, autocenter).
void UinputFfDevice::service() {
  input_event ev{};
  while (::read(fd_.get(), &ev, sizeof ev) == static_cast<ssize_t>(sizeof ev)) {
    if (ev.type == EV_UINPUT && ev.code == UI_FF_UPLOAD) upload_request(ev.value);
    if (ev.type == EV_UINPUT && ev.code == UI_FF_ERASE) erase_request(ev.value);
    if (ev.type != EV_FF) continue;
    if (ev.code == FF_GAIN) {
      gain_.store(ev.value);
    } else if (ev.code == FF_AUTOCENTER) {
      autocenter_.store(ev.value);
    } else if (ev.code < effects_.size()) {
      const std::lock_guard lock(m_);
      Effect& e = effects_[ev.code];
      if (e.playing && ev.value == 0) stops_.push_back({now_ns(), uploads_.size()});
      e.playing = ev.value > 0 && e.used;
    }
  }
}

void UinputFfDevice::step(double dt) {
  double force = 0.0;
  bool playing = false;
  int held = 0;
  const std::lock_guard lock(m_);
  for (const Effect& e : effects_) {
    held += e.used ? 1 : 0;
    if (!e.used || !e.playing) continue;
    playing = true;
    // 0x4000 is "left", toward -X (the header quotes <linux/input.h>).
    const double along = -std::sin(e.direction / 65536.0 * 2.0 * std::numbers::pi);
    force += e.level / 32767.0 * o_.full_scale * along * gain_.load() / 65535.0;
  }
  const double push = push_.load(), b = o_.damping + hand_damping_.load();
  v_ += dt / o_.mass * (force + push - b * v_);  // semi-implicit Euler
  x_ += dt * v_;
  force_.store(force);
  playing_.store(playing);
  held_.store(held);
}

void UinputFfDevice::run() {
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / o_.rate_hz));
  auto next = std::chrono::steady_clock::now();
  auto last = next;
  while (!stop_.load()) {
    pollfd p{fd_.get(), POLLIN, 0};
    ::poll(&p, 1, poll_timeout_ms(next));
    service();
    if (pending_ && std::chrono::steady_clock::now() >= pending_due_) finish_upload();
    const auto now = std::chrono::steady_clock::now();
    if (now < next) continue;
    // Integrated over the time that really passed: the axis moves whether or not this
    // thread was scheduled on time.
    step(std::min(0.01, std::chrono::duration<double>(now - last).count()));
    last = now;
    next += period;
    if (next < now) next = now + period;
    if (!silent_.load()) emit(EV_ABS, ABS_X, 0);
  }
}

}  // namespace hapticd::reference
