#include "drivers/evdev/socket_transport.h"

#include <poll.h>
#include <sys/socket.h>

#include <cerrno>

#include "base/errno_text.h"
#include "drivers/device.h"

namespace hapticd::drivers::evdev {

using wire::Type;

SocketTransport::SocketTransport(io::UniqueFd fd, std::chrono::milliseconds timeout)
    : fd_(std::move(fd)), timeout_(timeout) {
  hand_over_answers();
}

// The device's end of a new socketpair, passed to it with SCM_RIGHTS; this end stays.
void SocketTransport::hand_over_answers() {
  auto [mine, theirs] = io::seqpacket_pair();
  const auto type = static_cast<std::uint8_t>(Type::kAnswers);
  if (io::send_with_fd(fd_.get(), &type, 1, theirs.get()) < 0) {
    throw DeviceError("evdev loopback: the simulated device is gone: " + base::errno_text(errno));
  }
  answers_ = std::move(mine);  // theirs closes here: the device holds its own copy
}

int SocketTransport::send_bytes(const std::uint8_t* data, std::size_t size) noexcept {
  if (::send(fd_.get(), data, size, MSG_DONTWAIT | MSG_NOSIGNAL) >= 0) return 0;
  // The device's end is gone: as an unplugged device, ENODEV.
  return errno == EPIPE || errno == ECONNRESET ? ENODEV : errno;
}

wire::Message SocketTransport::request(const wire::Message& m, Type answer) {
  std::vector<std::uint8_t> bytes;
  wire::encode(m, bytes);
  if (const int e = send_bytes(bytes.data(), bytes.size()); e != 0) {
    throw DeviceError("evdev loopback: the simulated device is gone: " + base::errno_text(e));
  }
  const auto end = std::chrono::steady_clock::now() + timeout_;
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        end - std::chrono::steady_clock::now());
    pollfd p{fd_.get(), POLLIN, 0};
    if (left.count() <= 0 || ::poll(&p, 1, static_cast<int>(left.count())) == 0) {
      throw DeviceError("evdev loopback: the simulated device did not answer within " +
                        std::to_string(timeout_.count()) + " ms");
    }
    const ssize_t n = ::recv(fd_.get(), rx_.data(), rx_.size(), MSG_DONTWAIT);
    if (n == 0) throw DeviceError("evdev loopback: the simulated device is gone");
    if (n < 0) {
      if (errno == EAGAIN || errno == EINTR) continue;
      throw DeviceError("evdev loopback: " + base::errno_text(errno));
    }
    const auto reply = wire::decode({rx_.data(), static_cast<std::size_t>(n)});
    if (reply && reply->type == answer) return *reply;
  }
}

wire::Facts SocketTransport::facts(int code) {
  wire::Message m;
  m.type = Type::kQuery;
  m.a = code;
  return request(m, Type::kFacts).facts;
}

void SocketTransport::set_fuzz(int code, int fuzz) {
  throw DeviceError("evdev loopback: the simulated device filters nothing: no fuzz to set to " +
                    std::to_string(fuzz) + " on axis " + std::to_string(code));
}

void SocketTransport::grab(bool on) {
  wire::Message m;
  m.type = Type::kGrab;
  m.a = on ? 1 : 0;
  const wire::Message r = request(m, Type::kStatus);
  if (r.error == EBUSY) {
    throw DeviceError("evdev: another process has grabbed the device (EVIOCGRAB: " +
                      base::errno_text(EBUSY) + ")");
  }
  if (r.error != 0) throw DeviceError("evdev: EVIOCGRAB: " + base::errno_text(r.error));
}

int SocketTransport::upload(const wire::Effect& effect) {
  wire::Message m;
  m.type = Type::kUpload;
  m.effect = effect;
  const wire::Message r = request(m, Type::kStatus);
  if (r.error != 0) throw DeviceError("evdev: EVIOCSFF: " + base::errno_text(r.error));
  return r.b;
}

int SocketTransport::erase(int id) noexcept {
  try {
    wire::Message m;
    m.type = Type::kErase;
    m.a = id;
    return request(m, Type::kStatus).error;
  } catch (const std::exception&) {
    return ENODEV;
  }
}

// The update thread's: sends the update and waits for its answer, as EVIOCSFF does.
int SocketTransport::update(const wire::Effect& effect) noexcept {
  const std::size_t n = wire::encode_upload(effect, utx_);
  if (const int e = send_bytes(utx_.data(), n); e != 0) return e;
  return await_answer();
}

// The device's answer to the update just sent: 0 or its errno; ETIMEDOUT when none came within
// the time-out, ENODEV when the device is gone.
int SocketTransport::await_answer() noexcept {
  pollfd p{answers_.get(), POLLIN, 0};
  while (true) {
    const int r = ::poll(&p, 1, static_cast<int>(timeout_.count()));
    if (r < 0 && errno == EINTR) continue;
    if (r == 0) return ETIMEDOUT;
    if (r < 0) return errno;
    const ssize_t n = ::recv(answers_.get(), urx_.data(), urx_.size(), MSG_DONTWAIT);
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
    if (n <= 0) return n == 0 || errno == ECONNRESET ? ENODEV : errno;
    const auto m = wire::decode({urx_.data(), static_cast<std::size_t>(n)});
    if (!m || m->type != Type::kStatus) return EPROTO;  // a device that answers nonsense
    return m->error;
  }
}

int SocketTransport::write_ff(int code, int value) noexcept {
  const std::size_t n = wire::encode_write_ff(code, value, tx_);
  return send_bytes(tx_.data(), n);
}

ReadStatus SocketTransport::read(wire::Event& ev, int& error) noexcept {
  while (true) {
    const ssize_t n = ::recv(fd_.get(), rx_.data(), rx_.size(), MSG_DONTWAIT);
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return ReadStatus::kEmpty;
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error = n == 0 || errno == ECONNRESET ? ENODEV : errno;
      return ReadStatus::kError;
    }
    // Only an event is decoded here (a kFacts would allocate its strings); an answer here is
    // none the driver waits for.
    const auto m = static_cast<Type>(rx_[0]) == Type::kEvent
                       ? wire::decode({rx_.data(), static_cast<std::size_t>(n)})
                       : std::nullopt;
    if (!m) return ReadStatus::kMalformed;
    ev = m->event;
    return ev.type == kEvSyn && ev.code == kSynDropped ? ReadStatus::kDropped : ReadStatus::kEvent;
  }
}

void SocketTransport::set_emergency_effects(int first, int second) noexcept {
  stop_size_[0] = first < 0 ? 0 : wire::encode_write_ff(first, 0, stop_[0]);
  stop_size_[1] = second < 0 ? 0 : wire::encode_write_ff(second, 0, stop_[1]);
}

void SocketTransport::emergency() noexcept {
  for (std::size_t k = 0; k < stop_.size(); ++k) {
    if (stop_size_[k] == 0) continue;
    [[maybe_unused]] const ssize_t n =
        ::send(fd_.get(), stop_[k].data(), stop_size_[k], MSG_DONTWAIT | MSG_NOSIGNAL);
  }
}

}  // namespace hapticd::drivers::evdev
