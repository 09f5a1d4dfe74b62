#pragma once
// In-process CAN bus: any number of endpoints opened with the same name see each other's frames
// (not their own, like a real controller without loopback). Used by the simulator and tests.
#include <deque>
#include <memory>
#include <mutex>

#include "hal/can/can_bus.hpp"

namespace hal {

class VirtualCanBus final : public CanBus {
 public:
  // Each endpoint buffers up to this many frames; older ones are dropped (and counted) beyond.
  static constexpr size_t kRxCapacity = 4096;

  VirtualCanBus(std::string network, Clock& clock);
  ~VirtualCanBus() override;

  CanSendResult send(const CanFrame& frame) override;
  std::optional<StampedCanFrame> receive() override;
  [[nodiscard]] CanBusState state() const override;
  [[nodiscard]] CanStats stats() const override;
  [[nodiscard]] std::string name() const override { return "virtual:" + network_; }

  // Test hooks: simulate a bus-off of this endpoint's controller (sends fail, an error frame is
  // delivered), and recovery.
  void inject_bus_off(bool off);

  struct Network;

 private:
  void deliver(const CanFrame& frame, Nanos stamp);

  std::string network_;
  Clock& clock_;
  std::shared_ptr<Network> net_;
  mutable std::mutex mutex_;
  std::deque<StampedCanFrame> rx_;
  CanStats stats_;
  bool bus_off_ = false;
};

}  // namespace hal
