#include "hal/can/socketcan_bus.hpp"

#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <system_error>

#include "hal/kernel_stamp.hpp"

namespace hal::socketcan {

can_frame to_linux(const CanFrame& f) {
  can_frame out{};
  if (f.error) {
    out.can_id = (f.id & CAN_ERR_MASK) | CAN_ERR_FLAG;
  } else if (f.extended) {
    out.can_id = (f.id & CAN_EFF_MASK) | CAN_EFF_FLAG;
  } else {
    out.can_id = f.id & CAN_SFF_MASK;
  }
  if (f.remote) out.can_id |= CAN_RTR_FLAG;
  out.len = f.dlc > 8 ? 8 : f.dlc;
  std::memcpy(out.data, f.data.data(), 8);
  return out;
}

CanFrame from_linux(const can_frame& in) {
  CanFrame f;
  f.error = (in.can_id & CAN_ERR_FLAG) != 0;
  f.extended = !f.error && (in.can_id & CAN_EFF_FLAG) != 0;
  f.remote = (in.can_id & CAN_RTR_FLAG) != 0;
  f.id = f.error ? (in.can_id & CAN_ERR_MASK)
                 : (f.extended ? (in.can_id & CAN_EFF_MASK) : (in.can_id & CAN_SFF_MASK));
  f.dlc = in.len > 8 ? 8 : in.len;
  std::memcpy(f.data.data(), in.data, 8);
  return f;
}

std::vector<can_filter> make_filters(const std::vector<uint32_t>& standard_ids) {
  std::vector<can_filter> out;
  out.reserve(standard_ids.size());
  for (const uint32_t id : standard_ids) {
    // Match the id exactly, standard frames only (EFF flag must be clear), data or remote.
    out.push_back(can_filter{id & CAN_SFF_MASK, CAN_SFF_MASK | CAN_EFF_FLAG});
  }
  return out;
}

can_err_mask_t error_mask() {
  return CAN_ERR_TX_TIMEOUT | CAN_ERR_CRTL | CAN_ERR_ACK | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED;
}

ErrorFrameInfo decode_error_frame(const CanFrame& f) {
  ErrorFrameInfo e;
  if (!f.error) return e;
  auto add = [&](const char* t) { e.text += (e.text.empty() ? "" : ", ") + std::string(t); };
  if (f.id & CAN_ERR_TX_TIMEOUT) {
    e.tx_timeout = true;
    add("TX timeout");
  }
  if (f.id & CAN_ERR_LOSTARB) {
    e.lost_arbitration = true;
    add("lost arbitration");
  }
  if (f.id & CAN_ERR_CRTL) {
    e.controller = true;
    const uint8_t c = f.data[1];
    if (c & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW)) {
      e.rx_overflow = true;
      add("controller buffer overflow");
    }
    if (c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) {
      e.warning = true;
      add("error-warning");
    }
    if (c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) {
      e.passive = true;
      add("error-passive");
    }
    if (c == 0) add("controller problem");
  }
  if (f.id & CAN_ERR_ACK) {
    e.ack = true;
    add("no ACK (nothing else on the bus?)");
  }
  if (f.id & CAN_ERR_BUSOFF) {
    e.bus_off = true;
    add("bus-off");
  }
  if (f.id & CAN_ERR_RESTARTED) {
    e.restarted = true;
    add("controller restarted");
  }
  return e;
}

}  // namespace hal::socketcan

namespace hal {

SocketCanBus::SocketCanBus(int fd, std::string ifname, Clock& clock)
    : fd_(fd), ifname_(std::move(ifname)), clock_(clock) {}

SocketCanBus::~SocketCanBus() {
  close(fd_);
}

CanOpenResult SocketCanBus::open(const std::string& ifname, const std::vector<uint32_t>& filter_ids,
                                 Clock& clock) {
  auto errtext = [](int e) { return std::system_category().message(e); };
  const int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int e = errno;
    return {nullptr,
            "socketcan:" + ifname + ": cannot create a CAN socket (" + errtext(e) +
                (e == EAFNOSUPPORT ? "): this kernel has no CAN support (modprobe can-raw)" : ")")};
  }
  ifreq ifr{};
  ifname.copy(ifr.ifr_name, IFNAMSIZ - 1);
  if (ioctl(fd, SIOCGIFINDEX, &ifr) != 0) {
    close(fd);
    return {nullptr, "socketcan:" + ifname +
                         ": no such CAN interface (is the adapter plugged in "
                         "and the link up? see systemd/80-can0.network)"};
  }
  const auto filters = socketcan::make_filters(filter_ids);
  if (!filters.empty()) {
    setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
               static_cast<socklen_t>(filters.size() * sizeof(can_filter)));
  }
  const can_err_mask_t mask = socketcan::error_mask();
  setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, sizeof(mask));
  const int on = 1;
  setsockopt(fd, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof(on));
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  if (bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    const int e = errno;
    close(fd);
    return {nullptr, "socketcan:" + ifname + ": bind failed (" + errtext(e) + ")"};
  }
  return {std::make_unique<SocketCanBus>(fd, ifname, clock), ""};
}

CanSendResult SocketCanBus::send(const CanFrame& frame) {
  const can_frame cf = socketcan::to_linux(frame);
  const ssize_t n = write(fd_, &cf, sizeof(cf));
  if (n == static_cast<ssize_t>(sizeof(cf))) {
    ++stats_.frames_out;
    return CanSendResult::kOk;
  }
  if (n < 0 && (errno == ENOBUFS || errno == EAGAIN)) {
    // The queue is full of older frames; this (newer) one is dropped and the next command cycle
    // sends a fresher one. Never block the control task.
    ++stats_.tx_dropped;
    return CanSendResult::kQueueFull;
  }
  if (n < 0 && errno == ENETDOWN) {
    ++stats_.tx_dropped;
    return CanSendResult::kBusOff;
  }
  ++stats_.tx_errors;
  return CanSendResult::kError;
}

std::optional<StampedCanFrame> SocketCanBus::receive() {
  can_frame cf{};
  iovec iov{&cf, sizeof(cf)};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timeval))];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof(control);
  const ssize_t n = recvmsg(fd_, &msg, MSG_DONTWAIT);
  if (n < static_cast<ssize_t>(sizeof(cf))) {
    if (n >= 0) ++stats_.rx_dropped;
    return std::nullopt;
  }
  Nanos stamp = clock_.now();
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMP) {
      timeval tv{};
      std::memcpy(&tv, CMSG_DATA(c), sizeof(tv));
      const Nanos kernel(static_cast<int64_t>(tv.tv_sec) * 1'000'000'000 +
                         static_cast<int64_t>(tv.tv_usec) * 1000);
      stamp = monotonic_from_kernel_stamp(kernel, stamp);
    }
  }
  const CanFrame f = socketcan::from_linux(cf);
  if (f.error) {
    ++stats_.error_frames;
    const auto info = socketcan::decode_error_frame(f);
    if (info.bus_off) {
      if (state_ != CanBusState::kBusOff) ++stats_.bus_off_count;
      state_ = CanBusState::kBusOff;
    } else if (info.restarted) {
      state_ = CanBusState::kActive;
    } else if (info.passive) {
      state_ = CanBusState::kPassive;
    } else if (info.warning) {
      state_ = CanBusState::kWarning;
    }
  } else {
    ++stats_.frames_in;
  }
  return StampedCanFrame{f, stamp};
}

}  // namespace hal
