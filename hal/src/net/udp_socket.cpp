#include "hal/net/udp_socket.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <system_error>

#include "hal/kernel_stamp.hpp"

namespace hal {
namespace {

std::string errno_text() {
  return std::error_code(errno, std::generic_category()).message();
}

bool to_sockaddr(const UdpEndpoint& e, sockaddr_in& out) {
  out = sockaddr_in{};
  out.sin_family = AF_INET;
  out.sin_port = htons(e.port);
  return inet_pton(AF_INET, e.address.c_str(), &out.sin_addr) == 1;
}

// Large enough for any UDP payload we accept (1206/512 for the VLP-16); bigger is truncated.
constexpr size_t kMaxDatagram = 2048;

}  // namespace

bool parse_udp_endpoint(const std::string& text, UdpEndpoint& out, std::string& error) {
  std::string_view t = text;
  if (t.rfind("udp:", 0) == 0) t.remove_prefix(4);
  const size_t colon = t.rfind(':');
  if (colon == std::string_view::npos) {
    error = "'" + text + "': expected <address>:<port>";
    return false;
  }
  const std::string_view port = t.substr(colon + 1);
  unsigned value = 0;
  const auto [p, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (ec != std::errc() || p != port.data() + port.size() || value > 65535) {
    error = "'" + text + "': port '" + std::string(port) + "' is not 0..65535";
    return false;
  }
  UdpEndpoint e{std::string(t.substr(0, colon)), static_cast<uint16_t>(value)};
  sockaddr_in sa{};
  if (!to_sockaddr(e, sa)) {
    error = "'" + text + "': '" + e.address + "' is not an IPv4 address";
    return false;
  }
  out = e;
  return true;
}

UdpReceiver::UdpReceiver(int fd, uint16_t port, int buffer_bytes)
    : fd_(fd), port_(port), buffer_bytes_(buffer_bytes), buffer_(kMaxDatagram) {}

UdpReceiver::~UdpReceiver() {
  ::close(fd_);
}

UdpReceiver::OpenResult UdpReceiver::open(const UdpEndpoint& endpoint, int receive_buffer_bytes,
                                          UdpStamp stamp) {
  OpenResult r;
  sockaddr_in sa{};
  if (!to_sockaddr(endpoint, sa)) {
    r.error = "udp: '" + endpoint.address + "' is not an IPv4 address";
    return r;
  }
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    r.error = "udp: socket: " + errno_text();
    return r;
  }
  const int one = 1;
  // Sensors broadcast; several listeners (the daemon and a diagnostics tool) may share the port.
  (void)setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  if (stamp == UdpStamp::kKernel)
    (void)setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof(one));
  (void)setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof(one));
  // SO_RCVBUFFORCE passes net.core.rmem_max with CAP_NET_ADMIN; otherwise the capped request.
  if (setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &receive_buffer_bytes,
                 sizeof(receive_buffer_bytes)) != 0) {
    (void)setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receive_buffer_bytes,
                     sizeof(receive_buffer_bytes));
  }
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&sa), sizeof(sa)) != 0) {
    r.error = "udp: cannot bind " + endpoint.address + ":" + std::to_string(endpoint.port) + ": " +
              errno_text();
    ::close(fd);
    return r;
  }
  sockaddr_in bound{};
  socklen_t len = sizeof(bound);
  (void)getsockname(fd, reinterpret_cast<sockaddr*>(&bound), &len);
  int actual = 0;
  socklen_t alen = sizeof(actual);
  (void)getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &actual, &alen);
  r.receiver.reset(new UdpReceiver(fd, ntohs(bound.sin_port), actual));
  return r;
}

size_t UdpReceiver::drain(size_t max_datagrams, Nanos now,
                          const std::function<void(const UdpDatagram&)>& on) {
  size_t n_read = 0;
  while (n_read < max_datagrams) {
    sockaddr_in from{};
    iovec iov{buffer_.data(), buffer_.size()};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(uint32_t))];
    msghdr msg{};
    msg.msg_name = &from;
    msg.msg_namelen = sizeof(from);
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof(control);
    const ssize_t n = recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (n < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) ++stats_.errors;
      break;
    }
    ++n_read;
    UdpDatagram d;
    d.stamp = now;
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level != SOL_SOCKET) continue;
      if (c->cmsg_type == SO_TIMESTAMPNS) {
        timespec ts{};
        std::memcpy(&ts, CMSG_DATA(c), sizeof(ts));
        d.stamp = monotonic_from_kernel_stamp(
            Nanos(static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec), now);
      } else if (c->cmsg_type == SO_RXQ_OVFL) {
        uint32_t dropped = 0;
        std::memcpy(&dropped, CMSG_DATA(c), sizeof(dropped));
        // The kernel's count is cumulative for the socket (it wraps at 2^32).
        stats_.kernel_drops += static_cast<uint32_t>(dropped - last_ovfl_);
        last_ovfl_ = dropped;
      }
    }
    if ((msg.msg_flags & MSG_TRUNC) != 0) {
      ++stats_.truncated;
      continue;
    }
    ++stats_.datagrams;
    stats_.bytes += static_cast<uint64_t>(n);
    d.bytes = std::span<const uint8_t>(buffer_.data(), static_cast<size_t>(n));
    d.source_ipv4 = ntohl(from.sin_addr.s_addr);
    d.source_port = ntohs(from.sin_port);
    on(d);
  }
  return n_read;
}

std::unique_ptr<UdpSender> UdpSender::open(std::string& error) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    error = "udp: socket: " + errno_text();
    return nullptr;
  }
  const int one = 1;
  (void)setsockopt(fd, SOL_SOCKET, SO_BROADCAST, &one, sizeof(one));
  return std::unique_ptr<UdpSender>(new UdpSender(fd));
}

UdpSender::~UdpSender() {
  ::close(fd_);
}

bool UdpSender::send_to(const UdpEndpoint& to, std::span<const uint8_t> bytes) {
  sockaddr_in sa{};
  if (!to_sockaddr(to, sa)) return false;
  const ssize_t n = ::sendto(fd_, bytes.data(), bytes.size(), 0,
                             reinterpret_cast<const sockaddr*>(&sa), sizeof(sa));
  return n == static_cast<ssize_t>(bytes.size());
}

}  // namespace hal
