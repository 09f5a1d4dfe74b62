#pragma once
// A link that passes packets through unchanged and shows each received one to a callback:
// recording (`companion-tracker record`, `companiond --record`) without touching the driver.
#include <functional>
#include <memory>

#include "amfitrack/packet_link.hpp"

namespace amfitrack {

class TapLink final : public PacketLink {
 public:
  using OnReceive = std::function<void(const Packet&)>;
  // Owning the link, or borrowing one that outlives the tap.
  TapLink(std::unique_ptr<PacketLink> inner, OnReceive on_receive)
      : owned_(std::move(inner)), inner_(*owned_), on_receive_(std::move(on_receive)) {}
  TapLink(PacketLink& inner, OnReceive on_receive)
      : inner_(inner), on_receive_(std::move(on_receive)) {}

  void service(hal::Nanos now) override { inner_.service(now); }
  std::optional<Packet> receive() override {
    auto p = inner_.receive();
    if (p) on_receive_(*p);
    return p;
  }
  bool send(const Packet& p) override { return inner_.send(p); }
  [[nodiscard]] bool failed() const override { return inner_.failed(); }
  [[nodiscard]] FramingStats framing_stats() const override { return inner_.framing_stats(); }
  [[nodiscard]] const PacketLink& inner() const { return inner_; }

 private:
  std::unique_ptr<PacketLink> owned_;
  PacketLink& inner_;
  OnReceive on_receive_;
};

}  // namespace amfitrack
