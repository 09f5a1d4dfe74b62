#include "hal/can/virtual_can.hpp"

#include <algorithm>
#include <map>
#include <vector>

namespace hal {

struct VirtualCanBus::Network {
  std::mutex mutex;
  std::vector<VirtualCanBus*> endpoints;
};

namespace {

std::mutex g_registry_mutex;
std::map<std::string, std::weak_ptr<VirtualCanBus::Network>>& registry() {
  static std::map<std::string, std::weak_ptr<VirtualCanBus::Network>> networks;
  return networks;
}

}  // namespace

VirtualCanBus::VirtualCanBus(std::string network, Clock& clock)
    : network_(std::move(network)), clock_(clock) {
  {
    std::lock_guard lock(g_registry_mutex);
    auto& weak = registry()[network_];
    net_ = weak.lock();
    if (!net_) {
      net_ = std::make_shared<Network>();
      weak = net_;
    }
  }
  std::lock_guard lock(net_->mutex);
  net_->endpoints.push_back(this);
}

VirtualCanBus::~VirtualCanBus() {
  std::lock_guard lock(net_->mutex);
  auto& eps = net_->endpoints;
  eps.erase(std::remove(eps.begin(), eps.end(), this), eps.end());
}

void VirtualCanBus::deliver(const CanFrame& frame, Nanos stamp) {
  std::lock_guard lock(mutex_);
  if (rx_.size() >= kRxCapacity) {
    rx_.pop_front();
    ++stats_.rx_dropped;
  }
  rx_.push_back(StampedCanFrame{frame, stamp});
}

CanSendResult VirtualCanBus::send(const CanFrame& frame) {
  {
    std::lock_guard lock(mutex_);
    if (bus_off_) {
      ++stats_.tx_dropped;
      return CanSendResult::kBusOff;
    }
    ++stats_.frames_out;
  }
  const Nanos stamp = clock_.now();
  std::lock_guard lock(net_->mutex);
  for (VirtualCanBus* ep : net_->endpoints) {
    if (ep != this) ep->deliver(frame, stamp);
  }
  return CanSendResult::kOk;
}

std::optional<StampedCanFrame> VirtualCanBus::receive() {
  std::lock_guard lock(mutex_);
  if (rx_.empty()) return std::nullopt;
  StampedCanFrame f = rx_.front();
  rx_.pop_front();
  if (f.frame.error) {
    ++stats_.error_frames;
  } else {
    ++stats_.frames_in;
  }
  return f;
}

CanBusState VirtualCanBus::state() const {
  std::lock_guard lock(mutex_);
  return bus_off_ ? CanBusState::kBusOff : CanBusState::kActive;
}

CanStats VirtualCanBus::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void VirtualCanBus::inject_bus_off(bool off) {
  std::lock_guard lock(mutex_);
  if (off && !bus_off_) {
    ++stats_.bus_off_count;
    // As SocketCAN reports it: an error frame with CAN_ERR_BUSOFF (0x40).
    CanFrame err;
    err.error = true;
    err.id = 0x40;
    err.dlc = 8;
    rx_.push_back(StampedCanFrame{err, clock_.now()});
  }
  bus_off_ = off;
}

}  // namespace hal
