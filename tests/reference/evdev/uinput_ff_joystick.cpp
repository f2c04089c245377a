#include "uinput_ff_joystick.h"
#include "reference_clock.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <stdexcept>

namespace hapticd::reference {
namespace {

void check(int rc, const char* what) {
  if (rc < 0)
    throw std::runtime_error(std::string("uinput joystick: ") + what + ": " + std::strerror(errno));
}

constexpr std::array<int, 2> kCodes{ABS_X, ABS_Y};

}  // namespace

UinputFfJoystick::UinputFfJoystick(const UinputJoystickOptions& o)
    : o_(o), effects_(static_cast<std::size_t>(o.effects)) {
  fd_.reset(::open("/dev/uinput", O_RDWR | O_NONBLOCK | O_CLOEXEC));
  check(fd_.get(), "open /dev/uinput");
  const int fd = fd_.get();
  check(ioctl(fd, UI_SET_EVBIT, EV_ABS), "UI_SET_EVBIT EV_ABS");
  check(ioctl(fd, UI_SET_EVBIT, EV_FF), "UI_SET_EVBIT EV_FF");
  for (int bit : {FF_CONSTANT, FF_GAIN}) check(ioctl(fd, UI_SET_FFBIT, bit), "UI_SET_FFBIT");
  for (const int code : kCodes) {
    check(ioctl(fd, UI_SET_ABSBIT, code), "UI_SET_ABSBIT");
    uinput_abs_setup abs{};
    abs.code = static_cast<__u16>(code);
    abs.absinfo.minimum = o.axis_min;
    abs.absinfo.maximum = o.axis_max;
    check(ioctl(fd, UI_ABS_SETUP, &abs), "UI_ABS_SETUP");
  }
  uinput_setup setup{};
  setup.id = {BUS_VIRTUAL, o.vendor, o.product, 1};
  std::strncpy(setup.name, o.name.c_str(), UINPUT_MAX_NAME_SIZE - 1);
  setup.ff_effects_max = static_cast<__u32>(o.effects);
  check(ioctl(fd, UI_DEV_SETUP, &setup), "UI_DEV_SETUP");
  check(ioctl(fd, UI_DEV_CREATE), "UI_DEV_CREATE");
  char sysname[64] = {};
  check(ioctl(fd, UI_GET_SYSNAME(sizeof sysname - 1), sysname), "UI_GET_SYSNAME");
  namespace fs = std::filesystem;
  for (const auto& e : fs::directory_iterator(fs::path("/sys/class/input") / sysname)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("event", 0) == 0) event_path_ = "/dev/input/" + n;
  }
  if (event_path_.empty())
    throw std::runtime_error("uinput joystick: no event node for " + std::string(sysname));
  for (int i = 0; i < 200 && !fs::exists(event_path_); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));  // devtmpfs makes the node
  }
  report();  // the first report, so the kernel's values are the axes'
  thread_ = std::thread([this] { run(); });
}

UinputFfJoystick::~UinputFfJoystick() { unplug(); }

void UinputFfJoystick::unplug() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  if (!gone_.exchange(true)) ioctl(fd_.get(), UI_DEV_DESTROY);
  const std::lock_guard lock(m_);
  force_ = {0.0, 0.0};
  playing_.store(false);
}

void UinputFfJoystick::hand(double push_x, double push_y, double damping) {
  const std::lock_guard lock(m_);
  push_ = {push_x, push_y};
  hand_damping_ = damping;
}

double UinputFfJoystick::position(int axis) const {
  const std::lock_guard lock(m_);
  return x_[static_cast<std::size_t>(axis)];
}

double UinputFfJoystick::force(int axis) const {
  const std::lock_guard lock(m_);
  return force_[static_cast<std::size_t>(axis)];
}

std::vector<JoystickUpload> UinputFfJoystick::uploads() const {
  const std::lock_guard lock(m_);
  return uploads_;
}

std::size_t UinputFfJoystick::stops() const {
  const std::lock_guard lock(m_);
  return stops_;
}

int UinputFfJoystick::value_of(double x) const {
  const double span = o_.position_max - o_.position_min;
  const double v = o_.axis_min + (x - o_.position_min) / span * (o_.axis_max - o_.axis_min);
  return static_cast<int>(std::lround(
      std::clamp(v, static_cast<double>(o_.axis_min), static_cast<double>(o_.axis_max))));
}

void UinputFfJoystick::write_events(const input_event* ev, std::size_t n) {
  [[maybe_unused]] const ssize_t w = ::write(fd_.get(), ev, n * sizeof *ev);
}

// Each axis that changed, then SYN_REPORT; nothing when neither did (the kernel would pass
// nothing on either).
void UinputFfJoystick::report() {
  input_event ev[3]{};
  std::size_t n = 0;
  {
    const std::lock_guard lock(m_);
    for (std::size_t a = 0; a < 2; ++a) {
      const int value = a == 1 && stuck_y_ != 0x7fffffff ? stuck_y_ : value_of(x_[a]);
      if (value == reported_[a]) continue;
      reported_[a] = value;
      ev[n].type = EV_ABS;
      ev[n].code = static_cast<__u16>(kCodes[a]);
      ev[n].value = value;
      ++n;
    }
  }
  if (n == 0) return;
  ev[n].type = EV_SYN;
  ev[n].code = SYN_REPORT;
  write_events(ev, n + 1);
}

// ABS_Y stuck at a value far outside the range, or a flood of frames of such values and then
// silence (the silence makes the flood's last values the kernel's: they stand).
void UinputFfJoystick::corrupt() {
  if (const int v = jump_.exchange(0x7fffffff); v != 0x7fffffff) stuck_y_ = v;
  const int frames = flood_.exchange(0);
  const int scale = flood_scale_.load();
  for (int i = 0; i < frames; ++i) {
    const int a = ((i * 7919) % 2001 - 1000) * scale / 1000 * o_.axis_max;
    const input_event ev[3] = {
        {{}, EV_ABS, ABS_X, a}, {{}, EV_ABS, ABS_Y, -a}, {{}, EV_SYN, SYN_REPORT, 0}};
    write_events(ev, 3);
  }
  if (frames == 0) return;
  const int end = scale * o_.axis_max;  // the last frame: both axes far out
  const input_event last[3] = {
      {{}, EV_ABS, ABS_X, end}, {{}, EV_ABS, ABS_Y, -end}, {{}, EV_SYN, SYN_REPORT, 0}};
  write_events(last, 3);
  silent_.store(true);
}

// <linux/uinput.h>, "To implement upload_effect()": UI_BEGIN_FF_UPLOAD, the effect taken, the
// return code placed, UI_END_FF_UPLOAD.
void UinputFfJoystick::upload_request(int request) {
  uinput_ff_upload up{};
  up.request_id = static_cast<__u32>(request);
  if (ioctl(fd_.get(), UI_BEGIN_FF_UPLOAD, &up) < 0) return;
  const int id = up.effect.id;
  if (up.effect.type != FF_CONSTANT || id < 0 || id >= o_.effects) {
    up.retval = -EINVAL;
  } else {
    const std::lock_guard lock(m_);
    Effect& e = effects_[static_cast<std::size_t>(id)];
    e.used = true;
    e.level = up.effect.u.constant.level;
    e.direction = up.effect.direction;
    uploads_.push_back({now_ns(), id, e.level, e.direction});
  }
  ioctl(fd_.get(), UI_END_FF_UPLOAD, &up);
}

void UinputFfJoystick::erase_request(int request) {
  uinput_ff_erase er{};
  er.request_id = static_cast<__u32>(request);
  if (ioctl(fd_.get(), UI_BEGIN_FF_ERASE, &er) < 0) return;
  if (er.effect_id < effects_.size()) {
    const std::lock_guard lock(m_);
    effects_[er.effect_id] = {};
  }
  ioctl(fd_.get(), UI_END_FF_ERASE, &er);
}

// What the kernel passed to the device: uploads, erases, and the EV_FF events written to its
// node (play or stop an effect, the gain).
void UinputFfJoystick::service() {
  input_event ev{};
  while (::read(fd_.get(), &ev, sizeof ev) == static_cast<ssize_t>(sizeof ev)) {
    if (ev.type == EV_UINPUT && ev.code == UI_FF_UPLOAD) upload_request(ev.value);
    if (ev.type == EV_UINPUT && ev.code == UI_FF_ERASE) erase_request(ev.value);
    if (ev.type != EV_FF || ev.code == FF_GAIN || ev.code >= effects_.size()) continue;
    const std::lock_guard lock(m_);
    Effect& e = effects_[ev.code];
    if (e.playing && ev.value == 0) ++stops_;
    e.playing = ev.value > 0 && e.used;
  }
}

void UinputFfJoystick::step(double dt) {
  const std::lock_guard lock(m_);
  std::array<double, 2> f{};
  bool playing = false;
  int held = 0;
  for (const Effect& e : effects_) {
    held += e.used ? 1 : 0;
    if (!e.used || !e.playing) continue;
    playing = true;
    // (-sin d, cos d): 0x4000 "left" toward -x, 0x0000 "down" toward +y (the header above).
    const double d = e.direction / 65536.0 * 2.0 * std::numbers::pi;
    const double level = e.level / 32767.0 * o_.full_scale;
    f[0] += -std::sin(d) * level;
    f[1] += std::cos(d) * level;
  }
  for (std::size_t a = 0; a < 2; ++a) {
    const double b = o_.damping + hand_damping_;
    v_[a] += dt / o_.mass * (f[a] + push_[a] - b * v_[a]);  // semi-implicit Euler
    x_[a] += dt * v_[a];
  }
  force_ = f;
  playing_.store(playing);
  held_.store(held);
}

void UinputFfJoystick::run() {
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / o_.rate_hz));
  auto next = std::chrono::steady_clock::now();
  auto last = next;
  while (!stop_.load()) {
    const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(
        next - std::chrono::steady_clock::now());
    pollfd p{fd_.get(), POLLIN, 0};
    ::poll(&p, 1, static_cast<int>(std::max<std::int64_t>(0, wait.count())));
    service();
    const auto now = std::chrono::steady_clock::now();
    if (now < next) continue;
    // Integrated over the time that really passed: the grip moves whether or not this thread
    // was scheduled on time.
    step(std::min(0.01, std::chrono::duration<double>(now - last).count()));
    last = now;
    next += period;
    if (next < now) next = now + period;
    if (silent_.load()) continue;
    corrupt();
    if (!silent_.load()) report();
  }
}

}  // namespace hapticd::reference
