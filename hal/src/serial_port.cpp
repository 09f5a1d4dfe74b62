#include "hal/serial_port.hpp"

#include <fcntl.h>
#include <libserialport.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <system_error>

namespace hal {
namespace {

std::string errno_text(int err) {
  return std::system_category().message(err);
}

class LibSerialPort final : public SerialPort {
 public:
  explicit LibSerialPort(sp_port* port) : port_(port) {}
  ~LibSerialPort() override {
    sp_close(port_);
    sp_free_port(port_);
  }
  long read(uint8_t* buf, size_t len) override {
    const sp_return r = sp_nonblocking_read(port_, buf, len);
    if (r < 0) {
      error_ = sp_last_error_message();
      return -1;
    }
    return r;
  }
  long write(const uint8_t* buf, size_t len) override {
    const sp_return r = sp_nonblocking_write(port_, buf, len);
    if (r < 0) {
      error_ = sp_last_error_message();
      return -1;
    }
    return r;
  }
  [[nodiscard]] std::string backend() const override { return "libserialport"; }
  [[nodiscard]] std::string last_error() const override { return error_; }

 private:
  sp_port* port_;
  std::string error_;
};

class TermiosPort final : public SerialPort {
 public:
  explicit TermiosPort(int fd) : fd_(fd) {}
  ~TermiosPort() override { close(fd_); }
  long read(uint8_t* buf, size_t len) override {
    const ssize_t n = ::read(fd_, buf, len);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return 0;
      error_ = errno_text(errno);
      return -1;
    }
    return n;
  }
  long write(const uint8_t* buf, size_t len) override {
    const ssize_t n = ::write(fd_, buf, len);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return 0;
      error_ = errno_text(errno);
      return -1;
    }
    return n;
  }
  [[nodiscard]] std::string backend() const override { return "termios"; }
  [[nodiscard]] std::string last_error() const override { return error_; }

 private:
  int fd_;
  std::string error_;
};

speed_t termios_speed(int baud) {
  switch (baud) {
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 921600:
      return B921600;
    case 1000000:
      return B1000000;
    case 2000000:
      return B2000000;
    default:
      return B115200;
  }
}

SerialOpenResult open_termios(const std::string& path, int baud) {
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return {nullptr, path + ": " + errno_text(errno)};
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) {
    const int err = errno;
    close(fd);
    return {nullptr, path + ": not a terminal (" + errno_text(err) + ")"};
  }
  cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS);
  cfsetispeed(&tio, termios_speed(baud));
  cfsetospeed(&tio, termios_speed(baud));
  if (tcsetattr(fd, TCSANOW, &tio) != 0) {
    const int err = errno;
    close(fd);
    return {nullptr, path + ": cannot configure (" + errno_text(err) + ")"};
  }
  return {std::make_unique<TermiosPort>(fd), ""};
}

}  // namespace

std::unique_ptr<SerialPort> adopt_serial_fd(int fd) {
  fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
  return std::make_unique<TermiosPort>(fd);
}

SerialOpenResult open_serial(const std::string& path, int baud) {
  sp_port* port = nullptr;
  if (sp_get_port_by_name(path.c_str(), &port) != SP_OK) {
    // Not a port libserialport knows (a pseudo-terminal, or missing): termios decides.
    return open_termios(path, baud);
  }
  if (sp_open(port, SP_MODE_READ_WRITE) != SP_OK) {
    std::string err = path + ": " + sp_last_error_message();
    sp_free_port(port);
    return {nullptr, err};
  }
  sp_set_baudrate(port, baud);
  sp_set_bits(port, 8);
  sp_set_parity(port, SP_PARITY_NONE);
  sp_set_stopbits(port, 1);
  sp_set_flowcontrol(port, SP_FLOWCONTROL_NONE);
  return {std::make_unique<LibSerialPort>(port), ""};
}

}  // namespace hal
