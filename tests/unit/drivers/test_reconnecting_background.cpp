// ReconnectingLink in background mode: the opener runs on the link's own thread, never on the
// caller's (the 120 Hz tracker task); service() only collects finished attempts, without
// waiting. Run under ThreadSanitizer in CI.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "amfitrack/packet_link.hpp"

namespace am = amfitrack;
using namespace std::chrono_literals;
using hal::Nanos;

namespace {

class NullLink final : public am::PacketLink {
 public:
  std::optional<am::Packet> receive() override { return std::nullopt; }
  bool send(const am::Packet& /*p*/) override { return true; }
  [[nodiscard]] bool failed() const override { return false; }
  [[nodiscard]] am::FramingStats framing_stats() const override { return {}; }
};

TEST(ReconnectingLinkBackground, OpensOffTheCallersThreadAndNeverBlocksIt) {
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<int> attempts{0};
  std::atomic<bool> opened_on_caller{false};
  std::atomic<bool> release{false};
  am::ReconnectingLink link(
      [&]() {
        opened_on_caller = opened_on_caller || std::this_thread::get_id() == caller;
        const int n = ++attempts;
        am::OpenedLink o;
        if (n == 1) {
          o.error = "not plugged in";
          return o;
        }
        // The second attempt is slow (USB enumeration): it waits for the test's go.
        while (!release.load())
          std::this_thread::yield();
        o.link = std::make_unique<NullLink>();
        o.description = "slow device";
        return o;
      },
      am::ReconnectConfig{100ms, 400ms}, am::OpenMode::kBackground);

  Nanos now{0};
  link.service(now);  // hands the first attempt to the worker
  EXPECT_TRUE(link.failed());
  while (link.events().open_failures == 0) {  // spin on the link's progress, not on time
    link.service(now);
    std::this_thread::yield();
  }
  EXPECT_EQ(link.events().last_error, "not plugged in");
  // Next attempt after the back-off; while the slow open runs, service() keeps returning.
  now = 150ms;
  link.service(now);  // hands the second attempt to the worker
  while (attempts.load() < 2)
    std::this_thread::yield();  // the worker is inside the slow open
  for (int i = 0; i < 1000; ++i)
    link.service(now);
  EXPECT_FALSE(link.connected()) << "still opening: service() returned without waiting";
  release = true;
  while (!link.connected()) {
    link.service(now);
    std::this_thread::yield();
  }
  EXPECT_EQ(link.events().connects, 1U);
  EXPECT_EQ(link.events().description, "slow device");
  EXPECT_FALSE(opened_on_caller.load());
}

}  // namespace
