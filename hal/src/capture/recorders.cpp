#include "hal/capture/recorders.hpp"

#include <ctime>

namespace hal {

WallClockOffset::WallClockOffset() {
  timespec mono{};
  timespec wall{};
  clock_gettime(CLOCK_MONOTONIC, &mono);
  clock_gettime(CLOCK_REALTIME, &wall);
  offset_ = Nanos((static_cast<int64_t>(wall.tv_sec) - static_cast<int64_t>(mono.tv_sec)) *
                      1'000'000'000 +
                  (wall.tv_nsec - mono.tv_nsec));
}

RecordingCanBus::RecordingCanBus(std::unique_ptr<CanBus> inner, const std::string& path,
                                 std::string iface, Clock& clock)
    : inner_(std::move(inner)), writer_(path), iface_(std::move(iface)), clock_(clock) {}

void RecordingCanBus::log(const CanFrame& frame, Nanos monotonic) {
  const int64_t wall = wall_.to_wall(monotonic).count();
  CandumpRecord rec;
  rec.sec = wall / 1'000'000'000;
  rec.nsec = wall % 1'000'000'000;
  rec.iface = iface_;
  rec.frame = frame;
  writer_.write(rec);
}

CanSendResult RecordingCanBus::send(const CanFrame& frame) {
  const CanSendResult r = inner_->send(frame);
  if (r == CanSendResult::kOk) log(frame, clock_.now());  // what went on the bus
  return r;
}

std::optional<StampedCanFrame> RecordingCanBus::receive() {
  auto f = inner_->receive();
  if (f) log(f->frame, f->stamp);
  return f;
}

RecordingDatagramSource::RecordingDatagramSource(std::unique_ptr<DatagramSource> inner,
                                                 std::unique_ptr<PcapWriter> out, uint16_t to_port)
    : inner_(std::move(inner)), out_(std::move(out)), to_port_(to_port) {}

size_t RecordingDatagramSource::drain(size_t max_datagrams, Nanos now,
                                      const std::function<void(const UdpDatagram&)>& on) {
  return inner_->drain(max_datagrams, now, [&](const UdpDatagram& d) {
    scratch_.capture_time = wall_.to_wall(d.stamp);
    scratch_.source_ipv4 = d.source_ipv4;
    scratch_.destination_ipv4 = 0xFFFFFFFFU;  // the VLP-16 broadcasts by default
    scratch_.source_port = d.source_port;
    scratch_.destination_port = to_port_;
    scratch_.payload.assign(d.bytes.begin(), d.bytes.end());
    out_->write(scratch_);
    on(d);
  });
}

}  // namespace hal
