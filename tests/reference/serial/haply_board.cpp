#include "haply_board.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>

#include "reference_clock.h"

namespace hapticd::reference {
namespace {

constexpr double kMaxTorque = 0.123;  // MAX_TORQUE, N m (both boards)
constexpr std::int64_t kTickNs = 1'000'000;

// A float or double converted to int on the boards' Cortex-M (soft-float __aeabi_f2iz /
// __aeabi_d2iz): truncation, NaN to 0, saturation where C++ leaves it undefined.
std::int32_t arm_to_int(double v) {
  if (std::isnan(v)) return 0;
  if (v >= 2147483647.0) return std::numeric_limits<std::int32_t>::max();
  if (v <= -2147483648.0) return std::numeric_limits<std::int32_t>::min();
  return static_cast<std::int32_t>(v);
}

float float_at(const std::vector<std::uint8_t>& b, std::size_t at) {  // BytesToFloat
  std::uint32_t u = 0;
  for (int i = 3; i >= 0; --i) u = (u << 8) | b[at + static_cast<std::size_t>(i)];
  return std::bit_cast<float>(u);
}

void put_float(std::vector<std::uint8_t>& out, float f) {  // FloatToBytes
  const auto u = std::bit_cast<std::uint32_t>(f);
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(u >> (8 * i)));
}

}  // namespace

struct HaplyBoard::Port {
  // struct motor
  int motor_host = 0, motor_dir = 0;
  bool motor_pins = false;  // initialize_actuator has run: its PWM drives the motor
  bool dir_high = false;
  int duty = 0;
  float received = 0.0f;
  // struct enc
  int enc_host = 0, enc_dir = 0;
  float offset = 0.0f, resolution = 0.0f;
  bool made = false;  // `new Encoder` has run (before it, Enc is a null pointer)
  bool swapped = false;
  std::int32_t count_at_write = 0;
  std::int64_t edges_at_write = 0;
};

// A readBytes() the firmware is blocked in, and what it does with the bytes.
struct HaplyBoard::Pending {
  bool setup = false;
  std::size_t need = 0;
  std::vector<std::uint8_t> got;
  std::int64_t deadline_ns = 0;
  std::uint8_t address = 0;
  std::array<bool, 4> motors{}, encoders{};
};

HaplyBoard::HaplyBoard(int fd, HaplyBoardOptions options)
    : fd_(fd),
      o_(options),
      ports_(options.firmware == HaplyFirmware::kM0V03 ? 2 : 4),
      analog_pins_(options.firmware == HaplyFirmware::kM0V03 ? 5 : 12),
      pwm_levels_(options.firmware == HaplyFirmware::kM0V03 ? 1023 : 4095),
      plant_(options.joints, options.start_angles),
      port_(static_cast<std::size_t>(ports_)) {}

HaplyBoard::~HaplyBoard() { stop(); }

void HaplyBoard::start() {
  if (thread_.joinable()) return;
  waiter_.re_arm();
  {
    const std::lock_guard lock(m_);
    plant_ns_ = now_ns();
  }
  thread_ = std::thread([this] { run(); });
  run_as_device(thread_);
}

void HaplyBoard::stop() {
  if (!thread_.joinable()) return;
  waiter_.stop();
  thread_.join();
}

// The board: its loop services the serial port when there is input and the mechanics at least
// every millisecond (the plant moves under the PWM whatever the firmware is doing).
void HaplyBoard::run() {
  std::int64_t next = now_ns() + kTickNs;
  for (;;) {
    const bool listen = !silent_.load() && !lost_.load();
    const auto w = waiter_.wait(fd_, listen, next);
    if (w.stop) return;
    const std::int64_t now = now_ns();
    if (now >= next) next += kTickNs * ((now - next) / kTickNs + 1);
    const std::lock_guard lock(m_);
    advance_plant(now);
    if (w.lost) lost_.store(true);
    if (listen && w.input && !hung_ && !read_available(fd_, bytes_)) lost_.store(true);
    in_.insert(in_.end(), bytes_.begin(), bytes_.end());
    bytes_.clear();
    if (!silent_.load() && !hung_) firmware_loop(now);
  }
}

void HaplyBoard::advance_plant(std::int64_t now) {
  while (plant_ns_ < now) {
    const std::int64_t dt = std::min(now - plant_ns_, kTickNs);
    plant_.step(static_cast<double>(dt) * 1e-9, shaft_torques());
    plant_ns_ += dt;
  }
}

// loop(): a readBytes() in progress first (it returns when its bytes came, or when a byte took
// longer than the timeout), then each command byte in turn.
void HaplyBoard::firmware_loop(std::int64_t now) {
  while (!hung_) {
    if (!pending_) {
      if (in_.empty()) return;
      const std::uint8_t command = in_.front();
      in_.pop_front();
      dispatch(command, now);
      continue;
    }
    auto& p = *pending_;
    while (p.got.size() < p.need && !in_.empty()) {
      p.got.push_back(in_.front());
      in_.pop_front();
      p.deadline_ns = now + o_.stream_timeout_ms * 1'000'000;
    }
    if (p.got.size() < p.need) {
      if (now < p.deadline_ns) return;
      ++c_.short_reads;
      p.got.resize(p.need, 0);
    }
    const auto done = std::move(pending_);
    done->setup ? finish_setup(*done) : finish_write(*done);
  }
}

int HaplyBoard::serial_read() {  // SerialUSB.read()
  if (in_.empty()) {
    ++c_.empty_reads;
    return -1;
  }
  const int b = in_.front();
  in_.pop_front();
  return b;
}

void HaplyBoard::dispatch(std::uint8_t command, std::int64_t now) {
  switch (command) {
    case 0:  // reset_haply
      address_ = static_cast<std::uint8_t>(serial_read());
      forget_addresses();
      ++c_.resets;
      break;
    case 1:
      begin_setup(now);
      break;
    case 2:
      begin_write(now);
      break;
    default:
      ++c_.unknown_commands;
  }
}

void HaplyBoard::forget_addresses() {  // reset_device: addresses only, never a duty
  for (auto& p : port_) p.motor_host = p.enc_host = 0;
  sensor_host_.fill(0);
  pwm_host_.fill(0);
  pwm_pulse_.fill(0);
}

// setup_device up to its readBytes(): the parameters read one byte at a time.
void HaplyBoard::begin_setup(std::int64_t now) {
  forget_addresses();
  auto p = std::make_unique<Pending>();
  p->setup = true;
  p->address = static_cast<std::uint8_t>(serial_read());
  std::size_t encoders = 0;
  for (int kind = 0; kind < 2; ++kind) {  // mtr_parameters, then enc_parameters
    auto& active = kind == 0 ? p->motors : p->encoders;
    auto use = static_cast<std::uint8_t>(serial_read());
    std::size_t count = 0;
    for (int i = 0; i < ports_; ++i, use = static_cast<std::uint8_t>(use >> 1)) {
      active[static_cast<std::size_t>(i)] = (use & 1) != 0;
      count += use & 1;
    }
    // Directions go to the first `count` structs in order, whichever ports are in use.
    for (std::size_t i = 0; i < count; ++i) {
      (kind == 0 ? port_[i].motor_dir : port_[i].enc_dir) = serial_read();
    }
    if (kind == 1) encoders = count;
  }
  const auto sensors = static_cast<std::uint8_t>(serial_read());
  for (int i = 0; i < sensors; ++i) {  // setup_sensors: M0 remaps the M3's pin 54 to 14
    const auto pin = static_cast<std::uint8_t>(serial_read());
    const int index =
        o_.firmware == HaplyFirmware::kM0V03 ? static_cast<std::uint8_t>(pin - 40) - 14 : pin - 54;
    if (index >= 0 && index < analog_pins_)
      sensor_host_[static_cast<std::size_t>(index)] = p->address;
  }
  const auto pwms = static_cast<std::uint8_t>(serial_read());
  for (int i = 0; i < pwms; ++i) {  // setup_pwms
    const auto pin = static_cast<std::uint8_t>(serial_read());
    if (pin <= 13) pwm_host_[pin] = p->address;
  }
  p->need = encoders * 8;
  p->deadline_ns = now + o_.stream_timeout_ms * 1'000'000;
  pending_ = std::move(p);
}

// setup_device after its readBytes(): setup_encoders, initialize_encoder, setup_actuators.
void HaplyBoard::finish_setup(const Pending& p) {
  std::size_t j = 0;
  for (std::size_t i = 0; i < port_.size(); ++i) {
    Port& port = port_[i];
    if (p.encoders[i]) {
      port.enc_host = p.address;
      port.offset = float_at(p.got, j);
      port.resolution = float_at(p.got, j + 4);
      if (o_.firmware == HaplyFirmware::kM0V03) port.resolution /= 2;  // counts half the edges
      j += 8;
      port.made = true;  // new Encoder(enc1, enc2), A and B swapped for a direction above 0
      port.swapped = port.enc_dir > 0;
      port.count_at_write = arm_to_int(static_cast<double>(port.offset * port.resolution / 360));
      port.edges_at_write = edges(i);
    }
    if (p.motors[i]) {  // initialize_actuator: pwm_setup writes a zero duty (CC / SetDutyCycle)
      port.motor_host = p.address;
      port.motor_pins = true;
      port.duty = 0;
    }
  }
  address_ = p.address;
  ++c_.setups;
}

// write_states up to its readBytes(): the address, then a pulse byte per PWM pin of it.
void HaplyBoard::begin_write(std::int64_t now) {
  auto p = std::make_unique<Pending>();
  p->address = static_cast<std::uint8_t>(serial_read());
  for (std::size_t pin = 0; pin < pwm_host_.size(); ++pin) {
    if (pwm_host_[pin] == p->address) pwm_pulse_[pin] = static_cast<std::uint8_t>(serial_read());
  }
  const auto motors = std::count_if(port_.begin(), port_.end(),
                                    [&](const Port& m) { return m.motor_host == p->address; });
  if (motors == 0) ++c_.unaddressed_writes;
  p->need = static_cast<std::size_t>(motors) * 4;
  p->deadline_ns = now + o_.stream_timeout_ms * 1'000'000;
  pending_ = std::move(p);
}

// write_states after its readBytes(): a torque per motor of the address, in port order; then
// loop() answers at once (replyCode 1).
void HaplyBoard::finish_write(const Pending& p) {
  std::size_t j = 0;
  for (auto& port : port_) {
    if (port.motor_host != p.address) continue;
    create_torque(port, float_at(p.got, j));
    j += 4;
  }
  address_ = p.address;
  ++c_.writes;
  read_states();
}

void HaplyBoard::create_torque(Port& port, float torque) {
  port.received = torque;
  const bool output = port.motor_dir == 0;  // LOW, inverted for direction 0
  port.dir_high = torque <= 0 ? output : !output;
  float magnitude = torque > 0 ? torque : -torque;  // Arduino's abs() macro
  if (static_cast<double>(magnitude) > kMaxTorque) magnitude = static_cast<float>(kMaxTorque);
  const float scaled = static_cast<float>(pwm_levels_) * magnitude;  // int * float
  port.duty = arm_to_int(static_cast<double>(scaled) / kMaxTorque);  // float / double
}

// The quadrature edges an encoder on port `i` has seen from angle 0 (the M0 sees half).
std::int64_t HaplyBoard::edges(std::size_t i) const {
  const double theta = i < 2 ? plant_.angles()[i] : 0.0;  // M3 ports 3, 4: nothing attached
  const double per_turn =
      o_.firmware == HaplyFirmware::kM0V03 ? o_.encoder_resolution / 2 : o_.encoder_resolution;
  return static_cast<std::int64_t>(std::floor(theta / (2 * std::numbers::pi) * per_turn));
}

float HaplyBoard::read_encoder(std::size_t i) const {  // read_encoder_value
  const Port& port = port_[i];
  const std::int64_t moved = edges(i) - port.edges_at_write;
  const auto count =
      static_cast<std::int32_t>(port.count_at_write + (port.swapped ? -moved : moved));
  return static_cast<float>(360.0 * count / static_cast<double>(port.resolution));
}

// read_states: [address, a float per sensor of it (nothing is wired to them: 0), an angle per
// encoder of it]. An encoder holding the address with no Encoder made yet is a null pointer.
void HaplyBoard::read_states() {
  std::vector<std::uint8_t> out{address_};
  for (int i = 0; i < analog_pins_; ++i) {
    if (sensor_host_[static_cast<std::size_t>(i)] == address_) put_float(out, 0.0f);
  }
  for (std::size_t i = 0; i < port_.size(); ++i) {
    if (port_[i].enc_host != address_) continue;
    if (!port_[i].made) {
      hung_ = true;  // HardFault: nothing more is read or sent
      return;
    }
    const float angle = read_encoder(i);
    if (i < 2) reported_[i] = angle;
    put_float(out, angle);
  }
  if (corrupt_.load() > 0) {
    corrupt_.fetch_sub(1);
    out[0] ^= 0x80;
    ++c_.corrupted_replies;
  }
  if (lost_.load() || !write_frame(fd_, out)) {
    ++c_.dropped_replies;
    return;
  }
  ++c_.replies;
}

std::array<double, 2> HaplyBoard::shaft_torques() const {
  std::array<double, 2> t{};
  for (std::size_t i = 0; i < 2; ++i) {
    const Port& p = port_[i];
    if (!p.motor_pins) continue;  // no PWM set up on this motor's pin yet
    t[i] = (p.dir_high ? -1.0 : 1.0) * p.duty / pwm_levels_ * kMaxTorque;
  }
  return t;
}

std::array<double, 2> HaplyBoard::motor_torque() const {
  const std::lock_guard lock(m_);
  return shaft_torques();
}

std::array<float, 2> HaplyBoard::received_torque() const {
  const std::lock_guard lock(m_);
  return {port_[0].received, port_[1].received};
}

std::array<float, 2> HaplyBoard::reported_angles() const {
  const std::lock_guard lock(m_);
  return reported_;
}

HaplyBoardCounters HaplyBoard::counters() const {
  const std::lock_guard lock(m_);
  return c_;
}

bool HaplyBoard::configured() const {
  const std::lock_guard lock(m_);
  return std::any_of(port_.begin(), port_.end(),
                     [](const Port& p) { return p.motor_host != 0 || p.enc_host != 0; });
}

bool HaplyBoard::hung() const {
  const std::lock_guard lock(m_);
  return hung_;
}

}  // namespace hapticd::reference
