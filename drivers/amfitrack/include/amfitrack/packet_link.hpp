#pragma once
// How Amfiprot packets travel: as COBS frames on a serial port, or one per 64-byte HID report
// (hidapi). The device shell only sees packets. A ReconnectingLink reopens a link that failed
// (unplugged) with back-off, so the shell sees one link that is sometimes down.
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "amfitrack/amfiprot_codec.hpp"
#include "hal/clock.hpp"
#include "hal/hid/hid_device.hpp"
#include "hal/serial_port.hpp"

namespace amfitrack {

class PacketLink {
 public:
  virtual ~PacketLink() = default;
  // Called once per poll before receive(): a link may reconnect here (time passed in).
  virtual void service(hal::Nanos /*now*/) {}
  virtual std::optional<Packet> receive() = 0;  // non-blocking
  virtual bool send(const Packet& p) = 0;
  [[nodiscard]] virtual bool failed() const = 0;  // device gone (read/write error) or not open
  // Cumulative since construction (over reconnects too).
  [[nodiscard]] virtual FramingStats framing_stats() const = 0;
};

// COBS-framed packets on a serial port (UART mode, 115200 8N1 by default).
class SerialCobsLink final : public PacketLink {
 public:
  explicit SerialCobsLink(std::unique_ptr<hal::SerialPort> port) : port_(std::move(port)) {}
  std::optional<Packet> receive() override;
  bool send(const Packet& p) override;
  [[nodiscard]] bool failed() const override { return failed_; }
  [[nodiscard]] FramingStats framing_stats() const override { return decoder_.stats(); }

 private:
  std::unique_ptr<hal::SerialPort> port_;
  CobsStreamDecoder decoder_;
  bool failed_ = false;
};

// One packet per HID input report ([report id][length][packet][padding]); OUT reports
// [0x01][packet][zeros].
class HidPacketLink final : public PacketLink {
 public:
  explicit HidPacketLink(std::unique_ptr<hal::HidDevice> device) : device_(std::move(device)) {}
  std::optional<Packet> receive() override;
  bool send(const Packet& p) override;
  [[nodiscard]] bool failed() const override { return failed_; }
  [[nodiscard]] FramingStats framing_stats() const override { return stats_; }

 private:
  std::unique_ptr<hal::HidDevice> device_;
  FramingStats stats_;
  bool failed_ = false;
};

struct OpenedLink {
  std::unique_ptr<PacketLink> link;
  std::string error;        // why it could not be opened
  std::string description;  // what was opened (e.g. "/dev/hidraw2 serial 0042")
};

struct ReconnectConfig {
  hal::Nanos first_retry = std::chrono::milliseconds(250);
  hal::Nanos max_retry = std::chrono::seconds(4);  // the back-off doubles up to this
};

struct LinkEvents {
  uint64_t connects = 0;
  uint64_t disconnects = 0;
  uint64_t open_failures = 0;
  std::string last_error;
  std::string description;  // of the open link
};

// kBackground runs the opener on the link's own (non-real-time) thread: enumerating USB devices
// and opening them can take milliseconds, which must not happen inside the 120 Hz task. The
// task's service() then only hands over a finished attempt (try-lock, never blocks).
enum class OpenMode : uint8_t { kInline, kBackground };

class ReconnectingLink final : public PacketLink {
 public:
  using Opener = std::function<OpenedLink()>;
  ReconnectingLink(Opener opener, const ReconnectConfig& config, OpenMode mode = OpenMode::kInline);
  ~ReconnectingLink() override;
  ReconnectingLink(const ReconnectingLink&) = delete;
  ReconnectingLink& operator=(const ReconnectingLink&) = delete;

  void service(hal::Nanos now) override;
  std::optional<Packet> receive() override;
  bool send(const Packet& p) override;
  [[nodiscard]] bool failed() const override { return !link_ || link_->failed(); }
  [[nodiscard]] FramingStats framing_stats() const override;
  [[nodiscard]] const LinkEvents& events() const { return events_; }
  [[nodiscard]] bool connected() const { return !failed(); }
  [[nodiscard]] hal::Nanos next_attempt() const { return next_attempt_; }

 private:
  void accept(OpenedLink opened, hal::Nanos now);
  void worker();

  Opener opener_;
  ReconnectConfig config_;
  std::unique_ptr<PacketLink> link_;
  FramingStats closed_stats_;  // of links already closed
  LinkEvents events_;
  hal::Nanos backoff_{0};
  hal::Nanos next_attempt_{0};
  bool attempted_ = false;
  // background opening
  OpenMode mode_;
  bool in_flight_ = false;  // an attempt was handed to the worker (service side only)
  std::mutex mutex_;        // guards requested_, stop_, done_
  std::condition_variable wake_;
  bool requested_ = false;
  bool stop_ = false;
  std::optional<OpenedLink> done_;
  std::thread worker_;
};

}  // namespace amfitrack
