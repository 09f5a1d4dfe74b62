#include "amfitrack/packet_link.hpp"

#include <algorithm>
#include <array>

namespace amfitrack {

// ---- serial (COBS) -------------------------------------------------------------------------

std::optional<Packet> SerialCobsLink::receive() {
  if (auto p = decoder_.next()) return p;
  if (failed_) return std::nullopt;
  std::array<uint8_t, 1024> buf{};
  for (int reads = 0; reads < 8; ++reads) {  // bounded: a flooding device cannot stall the task
    const long n = port_->read(buf.data(), buf.size());
    if (n < 0) {
      failed_ = true;
      break;
    }
    if (n == 0) break;
    decoder_.feed(std::span<const uint8_t>(buf.data(), static_cast<size_t>(n)));
    if (static_cast<size_t>(n) < buf.size()) break;
  }
  return decoder_.next();
}

bool SerialCobsLink::send(const Packet& p) {
  if (failed_) return false;
  std::vector<uint8_t> frame = cobs_encode(encode_packet(p));
  frame.push_back(0);
  const long n = port_->write(frame.data(), frame.size());
  if (n < 0) failed_ = true;
  return n == static_cast<long>(frame.size());
}

// ---- HID -----------------------------------------------------------------------------------

std::optional<Packet> HidPacketLink::receive() {
  if (failed_) return std::nullopt;
  std::array<uint8_t, kHidReportSize> report{};
  // Bounded: at most this many bad reports are skipped per call (a babbling device cannot stall
  // the task); the next call continues.
  for (int reads = 0; reads < 16; ++reads) {
    const long n = device_->read(report);
    if (n < 0) {
      failed_ = true;
      return std::nullopt;
    }
    if (n == 0) return std::nullopt;
    ++stats_.frames;
    const ParsedPacket parsed =
        parse_hid_report(std::span<const uint8_t>(report.data(), static_cast<size_t>(n)));
    if (parsed.packet) return parsed.packet;
    ++stats_.bad_packet;
    ++stats_.packet_errors[static_cast<size_t>(parsed.error)];
  }
  return std::nullopt;
}

bool HidPacketLink::send(const Packet& p) {
  if (failed_) return false;
  const auto report = encode_hid_report(p);
  const long n = device_->write(report);
  if (n < 0) failed_ = true;
  return n == static_cast<long>(report.size());
}

// ---- reconnecting --------------------------------------------------------------------------

ReconnectingLink::ReconnectingLink(Opener opener, const ReconnectConfig& config, OpenMode mode)
    : opener_(std::move(opener)), config_(config), backoff_(config.first_retry), mode_(mode) {
  if (mode_ == OpenMode::kBackground) worker_ = std::thread([this] { worker(); });
}

ReconnectingLink::~ReconnectingLink() {
  if (worker_.joinable()) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_one();
    worker_.join();
  }
}

void ReconnectingLink::worker() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return requested_ || stop_; });
    if (stop_) return;
    requested_ = false;
    lock.unlock();
    OpenedLink opened = opener_();  // the slow part, off the caller's thread
    lock.lock();
    done_ = std::move(opened);
  }
}

void ReconnectingLink::accept(OpenedLink opened, hal::Nanos now) {
  if (opened.link) {
    link_ = std::move(opened.link);
    ++events_.connects;
    events_.description = opened.description;
    backoff_ = config_.first_retry;
    return;
  }
  ++events_.open_failures;
  events_.last_error = opened.error;
  next_attempt_ = now + backoff_;
  backoff_ = std::min(backoff_ * 2, config_.max_retry);
}

void ReconnectingLink::service(hal::Nanos now) {
  if (link_ && link_->failed()) {
    // Unplugged (or a read/write error): close it, keep its counters, retry after the back-off.
    closed_stats_ += link_->framing_stats();
    link_.reset();
    ++events_.disconnects;
    events_.last_error = "device lost: " + events_.description;
    backoff_ = config_.first_retry;
    next_attempt_ = now + backoff_;
    return;
  }
  if (link_) return;
  if (in_flight_) {
    // Collect a finished background attempt without ever waiting for the worker.
    std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock() || !done_) return;
    OpenedLink opened = std::move(*done_);
    done_.reset();
    lock.unlock();
    in_flight_ = false;
    accept(std::move(opened), now);
    return;
  }
  if (attempted_ && now < next_attempt_) return;
  attempted_ = true;
  if (mode_ == OpenMode::kBackground) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      requested_ = true;
    }
    wake_.notify_one();
    in_flight_ = true;
    return;
  }
  accept(opener_(), now);
}

std::optional<Packet> ReconnectingLink::receive() {
  if (!link_) return std::nullopt;
  return link_->receive();
}

bool ReconnectingLink::send(const Packet& p) {
  return link_ && link_->send(p);
}

FramingStats ReconnectingLink::framing_stats() const {
  FramingStats s = closed_stats_;
  if (link_) s += link_->framing_stats();
  return s;
}

}  // namespace amfitrack
