#include "hal/net/datagram_queue.hpp"

namespace hal {

void DatagramQueue::push(std::span<const uint8_t> bytes, Nanos arrival) {
  const std::scoped_lock lock(mutex_);
  if (queue_.size() >= capacity_) {
    ++stats_.kernel_drops;
    return;
  }
  std::vector<uint8_t> buffer;
  if (!spare_.empty()) {
    buffer = std::move(spare_.back());
    spare_.pop_back();
  }
  buffer.assign(bytes.begin(), bytes.end());
  queue_.push_back(Item{std::move(buffer), arrival});
}

size_t DatagramQueue::drain(size_t max_datagrams, Nanos now,
                            const std::function<void(const UdpDatagram&)>& on) {
  size_t n = 0;
  while (n < max_datagrams) {
    Item item;
    {
      const std::scoped_lock lock(mutex_);
      if (queue_.empty() || queue_.front().arrival > now) break;
      item = std::move(queue_.front());
      queue_.pop_front();
      ++stats_.datagrams;
      stats_.bytes += item.bytes.size();
    }
    on(UdpDatagram{item.bytes, item.arrival, 0x7F000001U, 2368});
    ++n;
    const std::scoped_lock lock(mutex_);
    spare_.push_back(std::move(item.bytes));
  }
  return n;
}

UdpStats DatagramQueue::stats() const {
  const std::scoped_lock lock(mutex_);
  return stats_;
}

}  // namespace hal
