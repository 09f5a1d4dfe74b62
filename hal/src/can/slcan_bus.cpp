#include "hal/can/slcan_bus.hpp"

#include <array>

namespace hal {
namespace {
// Backlog beyond which the adapter is not keeping up: new frames are dropped, not queued.
constexpr size_t kMaxBacklog = 512;
}  // namespace

SlcanBus::SlcanBus(std::unique_ptr<SerialPort> port, std::string device, Clock& clock)
    : port_(std::move(port)), device_(std::move(device)), clock_(clock) {}

CanOpenResult SlcanBus::open(const std::string& device, int baud, int bitrate_kbps, Clock& clock) {
  const auto rate = slcan::bitrate_command(bitrate_kbps);
  if (!rate) return {nullptr, "slcan: unsupported bit rate " + std::to_string(bitrate_kbps)};
  SerialOpenResult s = open_serial(device, baud);
  if (!s.port) return {nullptr, "slcan: " + s.error};
  auto bus = std::make_unique<SlcanBus>(std::move(s.port), device, clock);
  // "\r\r\r" flushes whatever half-command the adapter holds; then close, set rate, open.
  if (!bus->write_all("\r\r\rC\r" + *rate + "\rO\r")) {
    return {nullptr, "slcan: " + device + ": write failed: " + bus->port_->last_error()};
  }
  return {std::move(bus), ""};
}

bool SlcanBus::write_all(const std::string& text) {
  tx_backlog_ += text;
  while (!tx_backlog_.empty()) {
    const long n =
        port_->write(reinterpret_cast<const uint8_t*>(tx_backlog_.data()), tx_backlog_.size());
    if (n < 0) {
      failed_ = true;
      return false;
    }
    if (n == 0) break;  // port busy: keep the rest for the next call
    tx_backlog_.erase(0, static_cast<size_t>(n));
  }
  return true;
}

CanSendResult SlcanBus::send(const CanFrame& frame) {
  if (failed_) return CanSendResult::kClosed;
  const auto text = slcan::encode(frame);
  if (!text) {
    ++stats_.tx_errors;
    return CanSendResult::kError;
  }
  if (tx_backlog_.size() > kMaxBacklog) {
    ++stats_.tx_dropped;
    return CanSendResult::kQueueFull;
  }
  if (!write_all(*text)) {
    ++stats_.tx_errors;
    return CanSendResult::kError;
  }
  ++stats_.frames_out;
  return CanSendResult::kOk;
}

void SlcanBus::pump() {
  if (failed_) return;
  if (!tx_backlog_.empty()) write_all("");
  std::array<uint8_t, 512> buf{};
  for (;;) {
    const long n = port_->read(buf.data(), buf.size());
    if (n < 0) {
      failed_ = true;  // unplugged adapter: EIO
      return;
    }
    if (n == 0) return;
    parser_.feed(
        std::string_view(reinterpret_cast<const char*>(buf.data()), static_cast<size_t>(n)));
  }
}

std::optional<StampedCanFrame> SlcanBus::receive() {
  pump();
  auto f = parser_.next_frame();
  if (!f) return std::nullopt;
  ++stats_.frames_in;
  return StampedCanFrame{*f, clock_.now()};
}

CanBusState SlcanBus::state() const {
  return failed_ ? CanBusState::kClosed : CanBusState::kActive;
}

CanStats SlcanBus::stats() const {
  CanStats s = stats_;
  s.rx_dropped = parser_.stats().malformed + parser_.stats().overlong;
  return s;
}

}  // namespace hal
