#include "vcan_interface.h"

#include <linux/if_link.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "sysfs.h"

namespace hapticd::kernel_test {
namespace {

// One rtnetlink request with attributes appended in place; enough for RTM_NEWLINK/DELLINK.
class LinkRequest {
 public:
  LinkRequest(std::uint16_t type, std::uint16_t flags) {
    auto* hdr = header();
    hdr->nlmsg_len = NLMSG_LENGTH(sizeof(ifinfomsg));
    hdr->nlmsg_type = type;
    hdr->nlmsg_flags = static_cast<std::uint16_t>(NLM_F_REQUEST | NLM_F_ACK | flags);
  }
  ifinfomsg* info() { return reinterpret_cast<ifinfomsg*>(buf_ + NLMSG_HDRLEN); }
  rtattr* add(std::uint16_t type, const void* data, std::size_t len) {
    auto* attr = reinterpret_cast<rtattr*>(buf_ + NLMSG_ALIGN(header()->nlmsg_len));
    attr->rta_type = type;
    attr->rta_len = static_cast<std::uint16_t>(RTA_LENGTH(len));
    if (len > 0) std::memcpy(reinterpret_cast<char*>(attr) + RTA_LENGTH(0), data, len);
    header()->nlmsg_len = NLMSG_ALIGN(header()->nlmsg_len) + RTA_ALIGN(attr->rta_len);
    return attr;
  }
  void end_nest(rtattr* nest) {
    nest->rta_len =
        static_cast<std::uint16_t>(buf_ + header()->nlmsg_len - reinterpret_cast<char*>(nest));
  }
  // Sends the request and turns the kernel's acknowledgement into success or an exception.
  void execute(const std::string& what) {
    UniqueFd sock(::socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE));
    if (!sock) throw_errno("netlink socket");
    if (::send(sock.get(), buf_, header()->nlmsg_len, 0) < 0) throw_errno(what);
    alignas(nlmsghdr) char reply[4096];
    const ssize_t n = ::recv(sock.get(), reply, sizeof reply, 0);
    if (n < 0) throw_errno(what);
    const auto* hdr = reinterpret_cast<const nlmsghdr*>(reply);
    if (hdr->nlmsg_type != NLMSG_ERROR) throw KernelFacilityError(what + ": no netlink ack");
    const auto* err = reinterpret_cast<const nlmsgerr*>(reply + NLMSG_HDRLEN);
    if (err->error != 0) {
      errno = -err->error;
      throw_errno(what);
    }
  }

 private:
  nlmsghdr* header() { return reinterpret_cast<nlmsghdr*>(buf_); }
  alignas(nlmsghdr) char buf_[512] = {};
};

void set_option(int fd, int name, const void* value, socklen_t len, const char* what) {
  if (::setsockopt(fd, SOL_CAN_RAW, name, value, len) != 0) throw_errno(what);
}

}  // namespace

VcanInterface::VcanInterface(std::string name, bool fd_capable) : name_(std::move(name)) {
  require_path("/sys/module/can_raw", "SocketCAN CAN_RAW (the can_raw module)");
  require_path("/sys/module/vcan", "virtual CAN (the vcan module)");
  LinkRequest req(RTM_NEWLINK, NLM_F_CREATE | NLM_F_EXCL);
  req.info()->ifi_family = AF_UNSPEC;
  req.info()->ifi_flags = IFF_UP;
  req.info()->ifi_change = IFF_UP;
  req.add(IFLA_IFNAME, name_.c_str(), name_.size() + 1);
  const std::uint32_t mtu = fd_capable ? CANFD_MTU : CAN_MTU;
  req.add(IFLA_MTU, &mtu, sizeof mtu);
  rtattr* linkinfo = req.add(IFLA_LINKINFO, nullptr, 0);
  req.add(IFLA_INFO_KIND, "vcan", 4);
  req.end_nest(linkinfo);
  req.execute("create vcan interface " + name_);
  index_ = static_cast<int>(::if_nametoindex(name_.c_str()));
  if (index_ == 0) throw_errno("if_nametoindex " + name_);
}

VcanInterface::~VcanInterface() {
  try {
    LinkRequest req(RTM_DELLINK, 0);
    req.info()->ifi_family = AF_UNSPEC;
    req.info()->ifi_index = index_;
    req.execute("delete " + name_);
  } catch (const KernelFacilityError&) {
    // Nothing sensible to do in a destructor; the next fixture's NLM_F_EXCL would say so.
  }
}

CanRawSocket::CanRawSocket(const VcanInterface& iface, const CanRawOptions& options)
    : fd_(::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW)) {
  if (!fd_) throw_errno("socket(PF_CAN, SOCK_RAW, CAN_RAW)");
  const int on = options.fd_frames ? 1 : 0;
  set_option(fd_.get(), CAN_RAW_FD_FRAMES, &on, sizeof on, "CAN_RAW_FD_FRAMES");
  if (!options.filters.empty()) {
    set_option(fd_.get(), CAN_RAW_FILTER, options.filters.data(),
               static_cast<socklen_t>(options.filters.size() * sizeof(can_filter)),
               "CAN_RAW_FILTER");
  }
  set_option(fd_.get(), CAN_RAW_ERR_FILTER, &options.error_mask, sizeof options.error_mask,
             "CAN_RAW_ERR_FILTER");
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = iface.index();
  if (::bind(fd_.get(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    throw_errno("bind CAN_RAW to " + iface.name());
  }
}

void CanRawSocket::send(const can_frame& frame) {
  if (::write(fd_.get(), &frame, sizeof frame) != static_cast<ssize_t>(sizeof frame)) {
    throw_errno("write can_frame");
  }
}

void CanRawSocket::send(const canfd_frame& frame) {
  if (::write(fd_.get(), &frame, sizeof frame) != static_cast<ssize_t>(sizeof frame)) {
    throw_errno("write canfd_frame");
  }
}

std::optional<ReceivedCanFrame> CanRawSocket::receive(std::chrono::milliseconds timeout) {
  pollfd pfd{fd_.get(), POLLIN, 0};
  const int ready = ::poll(&pfd, 1, static_cast<int>(timeout.count()));
  if (ready < 0) throw_errno("poll CAN_RAW");
  if (ready == 0) return std::nullopt;
  ReceivedCanFrame out;
  const ssize_t n = ::read(fd_.get(), &out.frame, sizeof out.frame);
  if (n < 0) throw_errno("read CAN_RAW");
  if (n != CAN_MTU && n != CANFD_MTU) {
    throw KernelFacilityError("CAN_RAW read returned " + std::to_string(n) + " bytes");
  }
  out.is_fd = n == CANFD_MTU;
  return out;
}

can_err_mask_t CanRawSocket::error_mask() const {
  can_err_mask_t mask = 0;
  socklen_t len = sizeof mask;
  if (::getsockopt(fd_.get(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, &len) != 0) {
    throw_errno("getsockopt CAN_RAW_ERR_FILTER");
  }
  return mask;
}

}  // namespace hapticd::kernel_test
