#include "service/commands/peer_endpoint.h"

#include <linux/if_link.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

#include "base/errno_text.h"
#include "config/config_loader.h"
#include "drivers/device.h"
#include "drivers/io/unique_fd.h"
#include "gate/number_format.h"
#include "service/commands/peer_can_listen.h"

namespace hapticd::service {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void netlink_failed(const std::string& interface, const char* what, int e) {
  throw DeviceError("peer: cannot ask the kernel about " + interface + " (" + what +
                    "): " + base::errno_text(e));
}

// Calls f(type, payload, length) for each attribute of an rtattr list.
template <class F>
void for_each_attr(const char* p, std::size_t len, F f) {
  while (len >= sizeof(rtattr)) {
    rtattr a;
    std::memcpy(&a, p, sizeof a);
    if (a.rta_len < sizeof(rtattr) || a.rta_len > len) return;
    f(a.rta_type, p + RTA_LENGTH(0), a.rta_len - RTA_LENGTH(0));
    const std::size_t step = RTA_ALIGN(a.rta_len);
    if (step >= len) return;
    p += step;
    len -= step;
  }
}

// The link kind inside IFLA_LINKINFO.
std::string link_kind(const char* p, std::size_t len) {
  std::string kind;
  for_each_attr(p, len, [&](unsigned type, const char* data, std::size_t n) {
    if (type == IFLA_INFO_KIND) kind.assign(data, strnlen(data, n));
  });
  return kind;
}

std::string driver_of(const fs::path& device) {
  std::error_code ec;
  const fs::path driver = fs::read_symlink(device / "driver", ec);
  return ec ? std::string() : driver.filename().string();
}

EndpointVerdict judge(const config::Config& cfg, const std::string& endpoint) {
  const std::string& driver = cfg.device.driver;
  if (driver == "can") return judge_can_link(endpoint, read_can_link(endpoint));
  if (driver == "gpio") {
    const std::string chip = endpoint.substr(0, endpoint.find(','));
    return judge_gpio_chip(chip, read_gpio_chip(chip));
  }
  if (driver == "hid") return judge_hid_endpoint(endpoint, read_udcs());
  return {EndpointVerdict::Kind::kReal,
          "hapticd cannot tell whether " + endpoint + " is a simulation for driver " + driver};
}

#if HAPTICD_WITH_CAN
void check_can_node(const config::Config& cfg, const std::string& interface, double seconds) {
  const auto& s = drivers::can::can_settings(cfg);
  spdlog::info("peer: listening {} s on {} for a node {} already there",
               gate::format_number(seconds), interface, s.node_id);
  if (const auto heard = listen_for_node(s, interface, seconds)) {
    throw DeviceError("peer: a node already answers at node id " + std::to_string(s.node_id) +
                      " on " + interface + " (heard " + describe_node_frame(*heard, s) +
                      "): a simulated drive there would answer beside it. Stop that node, or "
                      "give the peer another device.can.node_id");
  }
}
#endif

}  // namespace

CanLinkFacts read_can_link(const std::string& interface) {
  CanLinkFacts facts;
  const unsigned index = if_nametoindex(interface.c_str());
  if (index == 0) return facts;  // no such interface (or a name too long to be one)
  io::UniqueFd sock(::socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE));
  if (!sock) netlink_failed(interface, "socket", errno);
  struct {
    nlmsghdr header;
    ifinfomsg info;
  } request{};
  request.header.nlmsg_len = sizeof request;
  request.header.nlmsg_type = RTM_GETLINK;
  request.header.nlmsg_flags = NLM_F_REQUEST;
  request.info.ifi_family = AF_UNSPEC;
  request.info.ifi_index = static_cast<int>(index);
  if (::send(sock.get(), &request, sizeof request, 0) < 0) netlink_failed(interface, "send", errno);
  std::vector<char> buffer(32768);  // a link's whole description, statistics included
  const char* reply = buffer.data();
  const ssize_t n = ::recv(sock.get(), buffer.data(), buffer.size(), 0);
  if (n < 0) netlink_failed(interface, "recv", errno);
  nlmsghdr header;
  if (static_cast<std::size_t>(n) < sizeof header) netlink_failed(interface, "reply", EPROTO);
  std::memcpy(&header, reply, sizeof header);
  if (header.nlmsg_type == NLMSG_ERROR) {
    nlmsgerr err;
    std::memcpy(&err, reply + NLMSG_HDRLEN, sizeof err);
    if (err.error == -ENODEV) return facts;  // gone since if_nametoindex
    netlink_failed(interface, "RTM_GETLINK", -err.error);
  }
  const std::size_t fixed = NLMSG_HDRLEN + NLMSG_ALIGN(sizeof(ifinfomsg));
  if (header.nlmsg_type != RTM_NEWLINK || header.nlmsg_len > static_cast<std::size_t>(n) ||
      header.nlmsg_len < fixed) {
    netlink_failed(interface, "reply", EPROTO);
  }
  ifinfomsg info;
  std::memcpy(&info, reply + NLMSG_HDRLEN, sizeof info);
  facts.exists = true;
  facts.type = info.ifi_type;
  for_each_attr(reply + fixed, header.nlmsg_len - fixed,
                [&](unsigned type, const char* data, std::size_t len) {
                  if (type == IFLA_LINKINFO) facts.kind = link_kind(data, len);
                });
  return facts;
}

GpioChipFacts read_gpio_chip(const std::string& chip_dir) {
  GpioChipFacts facts;
  std::error_code ec;
  const fs::path dir = fs::canonical(chip_dir, ec);
  if (ec || !fs::is_directory(dir, ec)) return facts;
  facts.exists = true;
  const fs::path subsystem = fs::canonical(dir / "subsystem", ec);
  facts.is_gpio_chip =
      !ec && subsystem.filename() == "gpio" && subsystem.parent_path().filename() == "bus";
  facts.driver = driver_of(dir.parent_path());
  return facts;
}

std::vector<UdcFacts> read_udcs(const std::string& class_dir) {
  std::vector<UdcFacts> udcs;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(class_dir, ec)) {
    udcs.push_back({e.path().filename().string(), driver_of(e.path() / "device")});
  }
  return udcs;
}

void check_peer_endpoint(const config::Config& cfg, const std::string& endpoint,
                         const PeerEndpointPolicy& policy) {
  const EndpointVerdict v = judge(cfg, endpoint);
  switch (v.kind) {
    case EndpointVerdict::Kind::kUnusable:
      throw DeviceError("peer: " + v.what);
    case EndpointVerdict::Kind::kReal:
      if (!policy.impersonate_on_real_hardware) {
        throw config::ConfigError(
            {"peer: " + v.what +
             ": a simulated device there would stand in for hardware beside (or instead "
             "of) the real one. Use a simulated endpoint (vcan or vxcan, a gpio-sim chip, "
             "dummy_hcd, uhid), or say --impersonate-on-real-hardware if that is what you "
             "mean"});
      }
      spdlog::warn(
          "peer: {}: impersonating a device on real hardware, as "
          "--impersonate-on-real-hardware says",
          v.what);
      break;
    case EndpointVerdict::Kind::kSimulated:
      spdlog::info("peer: {}", v.what);
      break;
  }
#if HAPTICD_WITH_CAN
  if (cfg.device.driver == "can") check_can_node(cfg, endpoint, policy.listen_s);
#endif
}

}  // namespace hapticd::service
