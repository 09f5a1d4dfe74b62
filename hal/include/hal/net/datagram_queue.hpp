#pragma once
// An in-process datagram link: the simulated VLP-16 pushes packets stamped with their arrival
// time; the lidar task drains those that have arrived by its `now`. Bounded like a socket's
// receive buffer: pushes beyond the capacity are dropped and counted as kernel drops.
// Thread-safe (one producer, one consumer), so the world may run on its own thread in real time.
#include <deque>
#include <mutex>
#include <vector>

#include "hal/net/datagram_source.hpp"

namespace hal {

class DatagramQueue final : public DatagramSource {
 public:
  explicit DatagramQueue(size_t capacity_datagrams = 4096) : capacity_(capacity_datagrams) {}

  // Producer side.
  void push(std::span<const uint8_t> bytes, Nanos arrival);

  size_t drain(size_t max_datagrams, Nanos now,
               const std::function<void(const UdpDatagram&)>& on) override;
  [[nodiscard]] UdpStats stats() const override;

 private:
  struct Item {
    std::vector<uint8_t> bytes;
    Nanos arrival{0};
  };
  size_t capacity_;
  mutable std::mutex mutex_;
  std::deque<Item> queue_;
  std::vector<std::vector<uint8_t>> spare_;  // recycled buffers: no allocation once warm
  UdpStats stats_;
};

}  // namespace hal
