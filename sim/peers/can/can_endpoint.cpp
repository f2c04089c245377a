#include "sim/peers/can/can_endpoint.h"

#include <linux/if_link.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "base/errno_text.h"
#include "drivers/device.h"
#include "drivers/io/unique_fd.h"

namespace hapticd::sim {
namespace {

using Kind = EndpointVerdict::Kind;

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

EndpointVerdict judge_can_link(const std::string& interface, const CanLinkFacts& facts) {
  if (!facts.exists) return {Kind::kUnusable, "there is no network interface '" + interface + "'"};
  if (facts.type != kArphrdCan) {
    return {Kind::kUnusable, interface + " is not a CAN interface (link type " +
                                 std::to_string(facts.type) + ", CAN's is 280)"};
  }
  if (facts.kind == "vcan" || facts.kind == "vxcan") {
    return {Kind::kSimulated, interface + " is a virtual CAN bus (" + facts.kind + ")"};
  }
  if (facts.kind.empty()) {
    return {Kind::kReal, interface + " is a CAN interface of no link kind, not vcan or vxcan"};
  }
  return {Kind::kReal, interface + " is a CAN interface of link kind '" + facts.kind +
                           "' (a controller's), not vcan or vxcan"};
}

EndpointVerdict judge_can_endpoint(const config::Config&, const std::string& interface) {
  return judge_can_link(interface, read_can_link(interface));
}

}  // namespace hapticd::sim
