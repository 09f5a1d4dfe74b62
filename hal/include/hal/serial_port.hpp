#pragma once
// Serial ports, non-blocking, 8N1, no flow control. Real devices (USB-CDC, FTDI, on-board UARTs)
// are opened with libserialport. libserialport does not open pseudo-terminals (its maintainers
// consider them out of scope), so paths it cannot describe (e.g. /dev/pts/N used by tests and
// by socat bridges) are opened with plain termios instead; backend() says which.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace hal {

class SerialPort {
 public:
  virtual ~SerialPort() = default;
  // Non-blocking: bytes read/written (0 when nothing), or -1 on error (see last_error()).
  virtual long read(uint8_t* buf, size_t len) = 0;
  virtual long write(const uint8_t* buf, size_t len) = 0;
  [[nodiscard]] virtual std::string backend() const = 0;
  [[nodiscard]] virtual std::string last_error() const = 0;
};

struct SerialOpenResult {
  std::unique_ptr<SerialPort> port;
  std::string error;
};

SerialOpenResult open_serial(const std::string& path, int baud);
// Wraps an already open, non-blocking terminal fd (e.g. a pty master); takes ownership.
std::unique_ptr<SerialPort> adopt_serial_fd(int fd);

}  // namespace hal
