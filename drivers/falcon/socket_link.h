// The Falcon driver's transport over the loopback socketpair (falcon_transport.h): each FTDI
// request and bulk transfer one SOCK_SEQPACKET message, tagged as falcon_protocol.h's
// LoopbackTag says, to the simulated Falcon (sim/peers/falcon/) at the other end.
#pragma once

#include <array>
#include <memory>

#include "drivers/falcon/falcon_transport.h"
#include "drivers/io/unique_fd.h"

namespace hapticd::drivers::falcon {

class SocketLink final : public FalconTransport {
 public:
  explicit SocketLink(io::UniqueFd fd) : fd_(std::move(fd)) {}

  bool control(const FtdiRequest& r, std::string& error) override;
  bool write(std::span<const unsigned char> data, int timeout_ms, std::string& error) override;
  int read(std::span<unsigned char> buffer, int timeout_ms, std::string& error) override;

  std::string describe() const override { return "falcon (simulated, loopback)"; }
  TransportIo send(const Packet& p) noexcept override;
  TransportIo receive(PacketStream& stream) noexcept override;
  int error() const noexcept override { return error_; }
  std::int64_t received_ns() const noexcept override { return received_ns_; }
  void emergency(const Packet& p) noexcept override;

 private:
  bool send_message(unsigned char tag, std::span<const unsigned char> data, std::string& error);

  io::UniqueFd fd_;
  int error_ = 0;
  std::int64_t received_ns_ = 0;
  std::array<unsigned char, 1 + 8 * kUsbPacketBytes> rx_{};
};

}  // namespace hapticd::drivers::falcon
