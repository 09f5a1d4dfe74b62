#include <gtest/gtest.h>
#include <unistd.h>

#include "hal/sd_notify.hpp"
#include "support/notify_socket.hpp"

using namespace std::chrono_literals;

TEST(SystemdNotifier, SendsEachMessageToTheNotifySocket) {
  test_support::NotifySocket sock;
  ASSERT_TRUE(sock.ok());
  sock.export_env();
  hal::SystemdNotifier n;
  ASSERT_TRUE(n.enabled());

  EXPECT_TRUE(n.ready());
  EXPECT_EQ(sock.receive(1s), "READY=1");
  EXPECT_TRUE(n.watchdog());
  EXPECT_EQ(sock.receive(1s), "WATCHDOG=1");
  EXPECT_TRUE(n.status("HOLD: tracker silent | control 100Hz"));
  EXPECT_EQ(sock.receive(1s), "STATUS=HOLD: tracker silent | control 100Hz");
  EXPECT_TRUE(n.status("two\nlines"));
  EXPECT_EQ(sock.receive(1s), "STATUS=two lines") << "STATUS must stay one line";
  EXPECT_TRUE(n.ready_with_status("started"));
  EXPECT_EQ(sock.receive(1s), "READY=1\nSTATUS=started");
  EXPECT_TRUE(n.stopping());
  EXPECT_EQ(sock.receive(1s), "STOPPING=1");
  unsetenv("NOTIFY_SOCKET");
}

TEST(SystemdNotifier, IsANoOpWithoutSystemd) {
  unsetenv("NOTIFY_SOCKET");
  hal::SystemdNotifier n;
  EXPECT_FALSE(n.enabled());
  EXPECT_FALSE(n.ready());
  EXPECT_FALSE(n.watchdog());
}

TEST(SystemdNotifier, ReadsTheWatchdogIntervalForThisProcess) {
  setenv("WATCHDOG_USEC", "2000000", 1);
  setenv("WATCHDOG_PID", std::to_string(getpid()).c_str(), 1);
  const auto interval = hal::SystemdNotifier::watchdog_interval();
  ASSERT_TRUE(interval.has_value());
  EXPECT_EQ(*interval, 2s);
  setenv("WATCHDOG_PID", "1", 1);  // meant for another process
  EXPECT_FALSE(hal::SystemdNotifier::watchdog_interval().has_value());
  unsetenv("WATCHDOG_USEC");
  unsetenv("WATCHDOG_PID");
}
