#include "sim/sim_amfitrack.hpp"

#include <unistd.h>

#include <cerrno>
#include <cmath>

namespace sim {

namespace am = amfitrack;

namespace {

// The host's end of the in-process link.
class HostLink final : public am::PacketLink {
 public:
  HostLink(std::shared_ptr<void> keep, std::mutex& m, std::deque<am::Packet>& in,
           std::deque<am::Packet>& out)
      : keep_(std::move(keep)), mutex_(m), in_(in), out_(out) {}
  std::optional<am::Packet> receive() override {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (in_.empty()) return std::nullopt;
    am::Packet p = std::move(in_.front());
    in_.pop_front();
    ++stats_.frames;
    return p;
  }
  bool send(const am::Packet& p) override {
    const std::lock_guard<std::mutex> lock(mutex_);
    out_.push_back(p);
    return true;
  }
  [[nodiscard]] bool failed() const override { return false; }
  [[nodiscard]] am::FramingStats framing_stats() const override {
    const std::lock_guard<std::mutex> lock(mutex_);
    return stats_;
  }

 private:
  std::shared_ptr<void> keep_;  // the queues outlive the device if the host link does
  std::mutex& mutex_;           // NOLINT(cppcoreguidelines-avoid-const-or-ref-data-members)
  std::deque<am::Packet>& in_;
  std::deque<am::Packet>& out_;
  am::FramingStats stats_;
};

am::Packet reply(uint8_t source, uint8_t number, std::vector<uint8_t> payload) {
  am::Packet p;
  p.header.payload_length = static_cast<uint8_t>(payload.size());
  p.header.ack = am::AckType::kReply;
  p.header.packet_number = number;
  p.header.payload_type = am::payload_type::kCommon;
  p.header.source = source;
  p.header.destination = am::kPcTxId;
  p.payload = std::move(payload);
  return p;
}

void put_u32(std::vector<uint8_t>& v, uint32_t x) {
  for (int i = 0; i < 4; ++i)
    v.push_back(static_cast<uint8_t>(x >> (8 * i)));
}

}  // namespace

SimAmfitrack::SimAmfitrack(const SimAmfitrackConfig& config)
    : config_(config),
      q_(std::make_shared<Queues>()),
      rng_(config.seed),
      gyro_rng_(config.seed ^ 0x9e3779b9U) {}

void SimAmfitrack::set_sensor_pose(double x_m, double y_m, double z_m, double yaw_rad) {
  position_m_ = {x_m, y_m, z_m};
  quaternion_xyzw_ = {0, 0, std::sin(yaw_rad / 2), std::cos(yaw_rad / 2)};
}

void SimAmfitrack::set_sensor_pose(const std::array<double, 3>& position_m,
                                   const std::array<double, 4>& quaternion_xyzw) {
  position_m_ = position_m;
  quaternion_xyzw_ = quaternion_xyzw;
}

std::unique_ptr<am::PacketLink> SimAmfitrack::host_link() {
  return std::make_unique<HostLink>(q_, q_->mutex, q_->to_host, q_->from_host);
}

void SimAmfitrack::emit(am::Packet p) {
  const std::lock_guard<std::mutex> lock(q_->mutex);
  q_->to_host.push_back(std::move(p));
}

am::SensorMeasurement SimAmfitrack::measurement() {
  am::SensorMeasurement m;
  m.position_m = position_m_;
  m.quaternion_xyzw = quaternion_xyzw_;
  if (config_.position_noise_m > 0) {
    for (double& v : m.position_m)
      v += config_.position_noise_m * unit_(rng_);
  }
  if (config_.heading_noise_rad > 0) {
    // A small rotation about z, composed on the left (q_noise * q).
    const double a = config_.heading_noise_rad * unit_(rng_) / 2;
    const double s = std::sin(a);
    const double c = std::cos(a);
    const auto& q = quaternion_xyzw_;
    m.quaternion_xyzw = {c * q[0] - s * q[1], c * q[1] + s * q[0], c * q[2] + s * q[3],
                         c * q[3] - s * q[2]};
  }
  m.sensor_status = static_cast<uint8_t>((source_connected_ ? 0x08 : 0x00) |
                                         (static_cast<uint8_t>(bfield_) << 4));
  m.tracked_source = config_.source_tx_id;
  m.accel_g = {0, 0, 1};
  for (size_t i = 0; i < 3; ++i) {
    m.gyro_dps[i] = gyro_dps_[i] + config_.gyro_bias_dps[i];
    if (config_.gyro_noise_dps > 0) m.gyro_dps[i] += config_.gyro_noise_dps * gyro_unit_(gyro_rng_);
  }
  m.temperature_c = 31.0;
  m.pose_state_raw = pose_state_;
  m.quality_raw = quality_;
  m.rssi = -40;
  m.frame_id = frame_id_;
  return m;
}

void SimAmfitrack::step(hal::Nanos now) {
  const auto period =
      std::chrono::duration_cast<hal::Nanos>(std::chrono::duration<double>(1.0 / config_.rate_hz));
  if (!started_) {
    started_ = true;
    next_frame_ = now;
  }
  while (next_frame_ <= now) {
    if (drop_ > 0) {
      --drop_;
    } else if (!silent_) {
      emit(am::sensor_measurement_packet(measurement(), config_.sensor_tx_id, packet_number_++));
      ++frames_sent_;
    }
    frame_id_ = (frame_id_ + 1) & 0xFFFFFF;
    next_frame_ += period;
  }
  std::deque<am::Packet> requests;
  {
    const std::lock_guard<std::mutex> lock(q_->mutex);
    requests.swap(q_->from_host);
  }
  for (const am::Packet& r : requests)
    answer(r);
}

void SimAmfitrack::answer(const am::Packet& request) {
  ++requests_;
  if (request.header.payload_type != am::payload_type::kCommon || request.payload.empty()) return;
  const uint8_t dst = request.header.destination;
  for (const uint8_t tx : {config_.source_tx_id, config_.sensor_tx_id}) {
    if (dst != tx && dst != am::kBroadcastTxId) continue;
    const uint8_t n = packet_number_++;
    switch (request.payload[0]) {
      case am::command::kRequestDeviceId: {
        std::vector<uint8_t> p{am::command::kReplyDeviceId, tx};
        put_u32(p, 0xA3F10000U + tx);
        put_u32(p, 0x00C0FFEEU);
        put_u32(p, 0x12345678U);
        emit(reply(tx, n, std::move(p)));
        break;
      }
      case am::command::kRequestFirmwareVersion: {
        std::vector<uint8_t> p{am::command::kReplyFirmwareVersion};
        for (uint32_t w : config_.firmware)
          put_u32(p, w);
        emit(reply(tx, n, std::move(p)));
        break;
      }
      case am::command::kRequestDeviceName: {
        const std::string& name =
            tx == config_.source_tx_id ? config_.source_name : config_.sensor_name;
        std::vector<uint8_t> p{am::command::kReplyDeviceName};
        p.insert(p.end(), name.begin(), name.end());
        p.push_back(0);
        emit(reply(tx, n, std::move(p)));
        break;
      }
      default: {
        am::Packet nack = reply(tx, n, {});
        nack.header.payload_type = am::payload_type::kNotImplemented;
        emit(std::move(nack));
        break;
      }
    }
  }
}

bool SimAmfitrack::pump_cobs(int fd) {
  // Device -> host: every queued packet as one COBS frame.
  {
    const std::lock_guard<std::mutex> lock(q_->mutex);
    while (!q_->to_host.empty()) {
      const auto frame = am::cobs_encode(am::encode_packet(q_->to_host.front()));
      cobs_out_.insert(cobs_out_.end(), frame.begin(), frame.end());
      cobs_out_.push_back(0);
      q_->to_host.pop_front();
    }
  }
  while (!cobs_out_.empty()) {
    const ssize_t n = ::write(fd, cobs_out_.data(), cobs_out_.size());
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) break;  // try again next pump
    if (n < 0) return false;
    cobs_out_.erase(cobs_out_.begin(), cobs_out_.begin() + n);
  }
  // Host -> device.
  std::array<uint8_t, 512> buf{};
  for (;;) {
    const ssize_t n = ::read(fd, buf.data(), buf.size());
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) break;
    if (n <= 0) return n == 0;
    cobs_in_.feed(std::span<const uint8_t>(buf.data(), static_cast<size_t>(n)));
  }
  const std::lock_guard<std::mutex> lock(q_->mutex);
  while (auto p = cobs_in_.next())
    q_->from_host.push_back(std::move(*p));
  return true;
}

}  // namespace sim
