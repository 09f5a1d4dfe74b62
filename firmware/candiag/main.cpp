// companion-candiag: CAN diagnostics for the AgileX Scout Mini, for technicians at the robot.
// Works on socketcan:<if>, slcan:<tty> and (for demos and tests) virtual:<name> with --sim, which
// puts the built-in simulated base on the same virtual bus.
//
//   companion-candiag --bus socketcan:can0 check
//   companion-candiag --bus slcan:/dev/ttyACM0 monitor
//   companion-candiag --bus virtual:demo --sim jog --vx 0.2 --duration-s 2
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <array>
#include <atomic>
#include <csignal>
#include <cstdarg>
#include <cstdio>
#include <memory>
#include <mutex>
#include <thread>

#include "firmware/tool_console.hpp"
#include "hal/can/can_bus.hpp"
#include "hal/can/candump_log.hpp"
#include "hal/linux_clock.hpp"
#include "scout_mini/scout_mini.hpp"
#include "sim/sim_scout_mini.hpp"

namespace {

namespace sm = scout_mini;
using hal::Nanos;
using namespace std::chrono_literals;

using firmware::tool::complain;
using firmware::tool::say;

// Exit codes: 0 ok, 1 check failed / jog aborted, 2 cannot talk to the base (no bus, no frames,
// wrong protocol), 3 usage.
constexpr int kExitFail = 1;
constexpr int kExitNoBase = 2;

// The built-in simulated base, stepped on its own thread every 5 ms (demo / tests).
class SimBase {
 public:
  SimBase(const std::string& network, hal::Clock& clock, const std::string& fault, bool v1)
      : clock_(clock), v1_(v1) {
    auto opened = hal::open_can("virtual:" + network, clock);
    bus_ptr_ = std::move(opened.bus);
    base_ = std::make_unique<sim::SimScoutMini>(*bus_ptr_);
    if (fault == "estop") base_->set_estop(true);
    if (fault == "rc") base_->set_rc_takeover(true);
    if (fault == "undervoltage") base_->set_under_voltage(true);
    if (fault == "motor") base_->inject_motor_fault(1);
    if (fault == "silent") base_->set_feedback_silent(true);
    thread_ = std::thread([this] { loop(); });
  }
  ~SimBase() {
    stop_ = true;
    thread_.join();
  }

 private:
  void loop() {
    hal::LinuxClock sleeper;
    Nanos next = clock_.now();
    while (!stop_) {
      if (v1_) {
        (void)bus_ptr_->send(
            hal::CanFrame::standard(sm::id::kV1SystemState, {0, 0, 0, 0, 0, 0, 0, 0}));
      } else {
        base_->step(clock_.now());
      }
      next += 5ms;
      sleeper.sleep_until(next);
    }
  }
  hal::Clock& clock_;
  bool v1_;
  std::unique_ptr<hal::CanBus> bus_ptr_;
  std::unique_ptr<sim::SimScoutMini> base_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

std::string fault_names(uint16_t word) {
  std::string out;
  for (int b = 0; b < 16; ++b) {
    const auto bit = static_cast<uint16_t>(1U << b);
    if ((word & bit) == 0) continue;
    const auto name = sm::fault_bit_name(bit);
    out += (out.empty() ? "" : ",") + (name.empty() ? fmt::format("bit{}", b) : std::string(name));
  }
  return out.empty() ? "none" : out;
}

std::string mode_name(uint8_t m) {
  switch (m) {
    case 0:
      return "standby";
    case 1:
      return "can";
    case 2:
      return "serial";
    case 3:
      return "remote_control";
    default:
      return fmt::format("unknown({})", m);
  }
}

std::string vehicle_name(sm::VehicleState v) {
  switch (v) {
    case sm::VehicleState::kNormal:
      return "normal";
    case sm::VehicleState::kEstop:
      return "estop";
    case sm::VehicleState::kException:
      return "exception";
  }
  return "unknown";
}

const std::vector<std::pair<uint32_t, double>>& expected_ids() {
  // id, minimum acceptable rate (Hz) — feedback periods from the protocol, with margin.
  static const std::vector<std::pair<uint32_t, double>> kIds{
      {0x211, 5}, {0x221, 30}, {0x251, 30}, {0x252, 30}, {0x253, 30}, {0x254, 30},
      {0x261, 5}, {0x262, 5},  {0x263, 5},  {0x264, 5},  {0x311, 30}};
  return kIds;
}

std::string json_state(const sm::ScoutMini& d, Nanos now) {
  const auto& s = d.state();
  std::string ids;
  for (const auto& [id, min_hz] : expected_ids()) {
    const auto& st = d.id_stats(id);
    ids += fmt::format(
        "{}\"0x{:03X}\":{{\"count\":{},\"rate_hz\":{:.1f},\"age_ms\":{}}}", ids.empty() ? "" : ",",
        id, st.count, st.rate_hz(),
        st.count ? fmt::format("{:.1f}", static_cast<double>((now - st.last).count()) * 1e-6)
                 : std::string("null"));
  }
  std::string motors;
  for (size_t i = 0; i < 4; ++i) {
    const auto& m = s.motors[i];
    motors += fmt::format(
        "{}{{\"rpm\":{},\"current_a\":{:.1f},\"driver_temp_c\":{},\"motor_temp_c\":{},"
        "\"driver_state\":{}}}",
        i ? "," : "", m.rpm, m.current_a, m.driver_temp_c, m.motor_temp_c, m.driver_state);
  }
  const auto bus = d.counters();
  return fmt::format(
      "{{\"system_state_seen\":{},\"vehicle_state\":\"{}\",\"control_mode\":\"{}\","
      "\"battery_v\":{:.1f},\"fault_word\":{},\"faults\":\"{}\",\"protocol_v1\":{},"
      "\"velocity\":{{\"vx_mps\":{:.3f},\"vy_mps\":{:.3f},\"wz_radps\":{:.3f}}},"
      "\"odom\":{{\"x_m\":{:.3f},\"y_m\":{:.3f},\"theta_rad\":{:.3f}}},"
      "\"wheel_odometer_mm\":{},\"motors\":[{}],\"ids\":{{{}}},"
      "\"bus\":{{\"state\":\"{}\",\"error_frames\":{},\"write_errors\":{}}}}}",
      s.system_state_seen, vehicle_name(s.vehicle_state), mode_name(s.control_mode_raw),
      s.battery_v, s.fault_word, fault_names(s.fault_word), s.protocol_v1, s.velocity.vx_mps,
      s.velocity.vy_mps, s.velocity.wz_radps, s.odom.x_m, s.odom.y_m, s.odom.theta_rad,
      s.wheel_odometer
          ? fmt::format("[{},{}]", s.wheel_odometer->left_mm, s.wheel_odometer->right_mm)
          : std::string("null"),
      motors, ids, hal::to_string(d.bus_state()), bus.error_frames, bus.write_errors);
}

std::string text_state(const sm::ScoutMini& d, Nanos now) {
  const auto& s = d.state();
  std::string out;
  out += fmt::format("vehicle {:<9} mode {:<14} battery {:5.1f} V   faults 0x{:04X} {}\n",
                     vehicle_name(s.vehicle_state), mode_name(s.control_mode_raw), s.battery_v,
                     s.fault_word, fault_names(s.fault_word));
  out += fmt::format("velocity vx {:+.3f} m/s  vy {:+.3f} m/s  wz {:+.3f} rad/s\n",
                     s.velocity.vx_mps, s.velocity.vy_mps, s.velocity.wz_radps);
  out += fmt::format("odometry x {:+.3f} m  y {:+.3f} m  theta {:+.3f} rad   wheels {} mm\n",
                     s.odom.x_m, s.odom.y_m, s.odom.theta_rad,
                     s.wheel_odometer ? fmt::format("L {} R {}", s.wheel_odometer->left_mm,
                                                    s.wheel_odometer->right_mm)
                                      : std::string("-"));
  for (size_t i = 0; i < 4; ++i) {
    const auto& m = s.motors[i];
    out += fmt::format(
        "motor {} rpm {:6} current {:5.1f} A  driver {:3} C  motor {:3} C  state 0x{:02X}\n", i + 1,
        m.rpm, m.current_a, m.driver_temp_c, m.motor_temp_c, m.driver_state);
  }
  for (const auto& [id, min_hz] : expected_ids()) {
    const auto& st = d.id_stats(id);
    out += fmt::format(
        "  0x{:03X} {:6} frames {:6.1f} Hz  age {}\n", id, st.count, st.rate_hz(),
        st.count ? fmt::format("{:.0f} ms", static_cast<double>((now - st.last).count()) * 1e-6)
                 : std::string("never"));
  }
  const auto c = d.counters();
  out += fmt::format(
      "bus {}  error frames {}  write errors {}  decode drops: wrong dlc {}, unknown id {}\n",
      hal::to_string(d.bus_state()), c.error_frames, c.write_errors,
      c.decode_errors[static_cast<size_t>(sm::DecodeError::kWrongDlc)],
      c.decode_errors[static_cast<size_t>(sm::DecodeError::kUnknownId)]);
  return out;
}

// Polls for `duration` (or until interrupted).
void listen(sm::ScoutMini& d, hal::Clock& clock, Nanos duration) {
  hal::LinuxClock sleeper;
  const Nanos end = clock.now() + duration;
  while (clock.now() < end && !firmware::tool::interrupted()) {
    d.poll(clock.now());
    sleeper.sleep_until(clock.now() + 5ms);
  }
  d.poll(clock.now());
}

std::string_view message_name(const sm::Feedback& m) {
  static constexpr std::array<std::string_view, 10> kNames{
      "system_state",    "motion_state",   "light_state", "rc_state",  "motor_high_speed",
      "motor_low_speed", "wheel_odometer", "version",     "bms_basic", "bms_status"};
  return kNames[m.index()];
}

bool nothing_heard(const sm::ScoutMini& d) {
  for (const auto& [id, hz] : expected_ids()) {
    if (d.id_stats(id).count > 0) return false;
  }
  return !d.state().protocol_v1;
}

int no_frames_error(const std::string& bus) {
  complain(
      "no Scout Mini frames on %s: is the base powered on, the bus wired (CAN_H/CAN_L, "
      "120 ohm termination) and the bit rate 500 kbit/s?\n",
      bus.c_str());
  return kExitNoBase;
}

}  // namespace

int run(int argc, char** argv) {
  CLI::App app{"companion-candiag - CAN diagnostics for the AgileX Scout Mini"};
  app.require_subcommand(1);
  std::string bus_uri = "socketcan:can0";
  bool with_sim = false;
  std::string sim_fault;
  bool sim_v1 = false;
  app.add_option("-b,--bus", bus_uri, "socketcan:<if> | slcan:<tty>[@baud] | virtual:<name>");
  app.add_flag("--sim", with_sim, "put the built-in simulated base on a virtual: bus (demo/tests)");
  app.add_option("--sim-fault", sim_fault, "fault of the simulated base")
      ->check(CLI::IsMember({"estop", "rc", "undervoltage", "motor", "silent"}));
  app.add_flag("--sim-v1", sim_v1, "simulated base speaks protocol V1");

  auto* monitor = app.add_subcommand("monitor", "live decoded view (refreshes in place)");
  bool once = false;
  bool json = false;
  double monitor_s = 0;
  monitor->add_flag("--once", once, "listen 0.5 s, print one snapshot, exit");
  monitor->add_flag("--json", json, "machine-readable output (one JSON object per snapshot)");
  monitor->add_option("--duration-s", monitor_s, "stop after this long (0: until Ctrl-C)");

  auto* check = app.add_subcommand("check", "listen, verify ids/rates/mode/faults; PASS/FAIL");
  double check_s = 2.0;
  check->add_option("--seconds", check_s, "listening time");

  auto* dump = app.add_subcommand("dump", "print received frames (decoded, or a candump log)");
  bool dump_candump = false;
  double dump_s = 0;
  std::string iface = "can0";
  dump->add_flag("--candump", dump_candump, "candump -l format (canplayer/log2asc read it)");
  dump->add_option("--seconds", dump_s, "stop after this long (0: until Ctrl-C)");
  int64_t dump_count = 0;
  dump->add_option("--count", dump_count, "stop after this many frames (candump -n; 0: no limit)")
      ->check(CLI::Range(int64_t{0}, int64_t{1000000000}));
  dump->add_option("--iface", iface, "interface name written in candump lines");

  auto* replay = app.add_subcommand("replay", "send a candump log with its original timing");
  std::string replay_file;
  replay->add_option("file", replay_file, "candump log")->required();

  auto* send = app.add_subcommand("send", "send one frame, e.g. 421#01");
  std::string send_frame;
  send->add_option("frame", send_frame, "III#HEX (cansend notation)")->required();

  auto* enable = app.add_subcommand("enable", "put the base in CAN command mode and confirm");
  auto* clear = app.add_subcommand("clear-faults", "send 0x441 (clear latched faults)");
  auto* version =
      app.add_subcommand("version", "request and print firmware versions (0x411/0x41A)");
  auto* lights = app.add_subcommand("lights", "set the lights (0x121)");
  int light_mode = 1;
  int brightness = 100;
  lights->add_option("--mode", light_mode, "0 off, 1 on, 2 breathing")->check(CLI::Range(0, 3));
  lights->add_option("--brightness", brightness, "0..100")->check(CLI::Range(0, 100));

  auto* jog =
      app.add_subcommand("jog", "drive briefly with a dead-man (Ctrl-C, timeout or fault stops)");
  double vx = 0, vy = 0, wz = 0, jog_s = 1.0;
  jog->add_option("--vx", vx, "m/s")->check(CLI::Range(-0.5, 0.5));
  jog->add_option("--vy", vy, "m/s")->check(CLI::Range(-0.5, 0.5));
  jog->add_option("--wz", wz, "rad/s")->check(CLI::Range(-1.0, 1.0));
  jog->add_option("--duration-s", jog_s, "seconds (max 10)")->check(CLI::Range(0.0, 10.0));
  CLI11_PARSE(app, argc, argv);

  firmware::tool::catch_interrupts();
  hal::LinuxClock clock;

  std::unique_ptr<SimBase> simbase;
  if (with_sim) {
    if (bus_uri.rfind("virtual:", 0) != 0) {
      complain("--sim needs a virtual:<name> bus\n");
      return 3;
    }
    simbase = std::make_unique<SimBase>(bus_uri.substr(8), clock, sim_fault, sim_v1);
  }
  // dump/send/replay see the whole bus; the Scout commands only need its feedback ids.
  const bool whole_bus =
      app.got_subcommand(dump) || app.got_subcommand(send) || app.got_subcommand(replay);
  auto opened = hal::open_can(bus_uri, clock,
                              whole_bus ? std::vector<uint32_t>{} : scout_mini::feedback_ids());
  if (!opened.bus) {
    complain("cannot open the bus: %s\n", opened.error.c_str());  // the error names the URI
    return kExitNoBase;
  }
  hal::CanBus& bus = *opened.bus;
  sm::ScoutConfig cfg;
  cfg.manage_mode = app.got_subcommand(enable) || app.got_subcommand(jog);
  cfg.limits = {0.5, 0.5, 1.0};  // jog limits, far below the base's
  sm::ScoutMini driver(bus, cfg);

  if (app.got_subcommand(monitor)) {
    if (once) {
      listen(driver, clock, 500ms);
      if (nothing_heard(driver)) return no_frames_error(bus_uri);
      say("%s\n",
          (json ? json_state(driver, clock.now()) : text_state(driver, clock.now())).c_str());
      return 0;
    }
    const Nanos end = monitor_s > 0 ? clock.now() + std::chrono::duration_cast<Nanos>(
                                                        std::chrono::duration<double>(monitor_s))
                                    : Nanos::max();
    while (!firmware::tool::interrupted() && clock.now() < end) {
      listen(driver, clock, 200ms);
      if (json) {
        say("%s\n", json_state(driver, clock.now()).c_str());
      } else {
        say("\x1b[H\x1b[2J%s (Ctrl-C to quit)\n%s", bus_uri.c_str(),
            text_state(driver, clock.now()).c_str());
      }
      (void)std::fflush(stdout);
    }
    return 0;
  }

  if (app.got_subcommand(check)) {
    listen(driver, clock,
           std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(check_s)));
    if (nothing_heard(driver)) return no_frames_error(bus_uri);
    bool ok = true;
    auto line = [&](bool pass, const std::string& what) {
      say("%s %s\n", pass ? "PASS" : "FAIL", what.c_str());
      ok = ok && pass;
    };
    const auto& s = driver.state();
    if (s.protocol_v1) {
      line(false,
           "protocol: the base speaks protocol V1 (id 0x151), which is not supported; update "
           "the base firmware to protocol V2");
      return kExitNoBase;
    }
    line(true, "protocol: V2");
    const Nanos now = clock.now();
    for (const auto& [id, min_hz] : expected_ids()) {
      const auto& st = driver.id_stats(id);
      const bool fresh = st.count > 0 && now - st.last < 500ms;
      line(fresh && st.rate_hz() >= min_hz,
           fmt::format("id 0x{:03X}: {} frames, {:.1f} Hz (>= {:.0f} Hz expected){}", id, st.count,
                       st.rate_hz(), min_hz, fresh || st.count == 0 ? "" : ", stale"));
    }
    line(s.system_state_seen && s.vehicle_state == sm::VehicleState::kNormal,
         "vehicle state: " + vehicle_name(s.vehicle_state));
    line(s.control_mode_raw != 3,
         "control mode: " + mode_name(s.control_mode_raw) +
             (s.control_mode_raw == 3 ? " (a person holds the remote: SWB up for CAN)" : ""));
    line(s.stopping_faults() == 0,
         fmt::format("faults: 0x{:04X} {}", s.fault_word, fault_names(s.fault_word)));
    line(s.battery_v > 22.0, fmt::format("battery: {:.1f} V", s.battery_v));
    line(bus.state() != hal::CanBusState::kBusOff && driver.counters().error_frames == 0,
         fmt::format("bus: {}, {} error frames", hal::to_string(bus.state()),
                     driver.counters().error_frames));
    say("%s\n", ok ? "check: PASS" : "check: FAIL");
    return ok ? 0 : kExitFail;
  }

  if (app.got_subcommand(dump)) {
    const Nanos end =
        dump_s > 0
            ? clock.now() + std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(dump_s))
            : Nanos::max();
    hal::LinuxClock sleeper;
    int64_t frames = 0;
    auto more = [&] { return dump_count == 0 || frames < dump_count; };
    while (!firmware::tool::interrupted() && clock.now() < end && more()) {
      while (more()) {
        auto rx = bus.receive();
        if (!rx) break;
        ++frames;
        if (dump_candump) {
          timespec rt{};
          clock_gettime(CLOCK_REALTIME, &rt);
          hal::CandumpRecord rec{rt.tv_sec, rt.tv_nsec, iface, rx->frame};
          say("%s\n", hal::format_candump_line(rec).c_str());
        } else {
          const auto d = sm::decode(rx->frame);
          const std::string what = d.message ? std::string(message_name(*d.message))
                                             : "dropped: " + std::string(sm::to_string(d.error));
          say("%.6f %s %s\n", static_cast<double>(rx->stamp.count()) * 1e-9,
              hal::to_cansend(rx->frame).c_str(), what.c_str());
        }
      }
      (void)std::fflush(stdout);
      sleeper.sleep_until(clock.now() + 2ms);
    }
    return 0;
  }

  if (app.got_subcommand(replay)) {
    hal::CandumpReader reader(replay_file);
    if (!reader.is_open()) {
      complain("cannot open %s\n", replay_file.c_str());
      return kExitNoBase;
    }
    hal::LinuxClock sleeper;
    const Nanos start = clock.now();
    int64_t first_ns = -1;
    uint64_t sent = 0;
    uint64_t failed = 0;
    int64_t last_ns = 0;
    while (auto rec = reader.next()) {
      if (firmware::tool::interrupted()) break;
      const int64_t t = rec->sec * 1'000'000'000 + rec->nsec;
      if (first_ns < 0) first_ns = t;
      last_ns = t;
      sleeper.sleep_until(start + Nanos(t - first_ns));  // original spacing, no drift
      if (rec->frame.error) continue;  // error frames are observations, not sendable
      if (bus.send(rec->frame) == hal::CanSendResult::kOk) {
        ++sent;
      } else {
        ++failed;
      }
    }
    say("replayed %llu frames (%llu failed, %llu malformed lines) in %.3f s; log span %.3f s\n",
        static_cast<unsigned long long>(sent), static_cast<unsigned long long>(failed),
        static_cast<unsigned long long>(reader.malformed()),
        static_cast<double>((clock.now() - start).count()) * 1e-9,
        first_ns < 0 ? 0.0 : static_cast<double>(last_ns - first_ns) * 1e-9);
    return failed == 0 ? 0 : kExitFail;
  }

  if (app.got_subcommand(send)) {
    hal::CandumpRecord rec;
    std::string err;
    if (hal::parse_candump_line("(0.000000) x " + send_frame, rec, err) !=
        hal::CandumpParse::kRecord) {
      complain("bad frame '%s': %s\n", send_frame.c_str(), err.c_str());
      return 3;
    }
    const auto r = bus.send(rec.frame);
    say("%s: %s\n", hal::to_cansend(rec.frame).c_str(), std::string(hal::to_string(r)).c_str());
    return r == hal::CanSendResult::kOk ? 0 : kExitFail;
  }

  if (app.got_subcommand(enable)) {
    listen(driver, clock, 500ms);
    if (nothing_heard(driver)) return no_frames_error(bus_uri);
    say("control mode: %s%s\n", mode_name(driver.state().control_mode_raw).c_str(),
        driver.state().rc_has_control() ? " (remote control has priority: release it / SWB up)"
                                        : "");
    return driver.state().in_can_mode() ? 0 : kExitFail;
  }
  if (app.got_subcommand(clear)) {
    listen(driver, clock, 200ms);
    const uint16_t before = driver.state().fault_word;
    driver.clear_faults(0);
    listen(driver, clock, 300ms);
    say("faults before 0x%04X, after 0x%04X (%s)\n", before, driver.state().fault_word,
        fault_names(driver.state().fault_word).c_str());
    return driver.state().stopping_faults() == 0 ? 0 : kExitFail;
  }
  if (app.got_subcommand(version)) {
    driver.request_version();
    listen(driver, clock, 500ms);
    if (!driver.state().version) {
      complain("no version reply (0x41A) within 0.5 s; newer firmware may answer 0x4A1 instead\n");
      return kExitFail;
    }
    const auto& v = *driver.state().version;
    auto ver = [](uint16_t x) { return fmt::format("{}.{}", x >> 8, x & 0xFF); };
    say("control hw %s, driver hw %s, control sw %s, driver sw %s\n", ver(v.control_hw).c_str(),
        ver(v.driver_hw).c_str(), ver(v.control_sw).c_str(), ver(v.driver_sw).c_str());
    return 0;
  }
  if (app.got_subcommand(lights)) {
    const auto r = driver.set_lights(
        light_mode != 0, static_cast<uint8_t>(light_mode), static_cast<uint8_t>(brightness),
        static_cast<uint8_t>(light_mode), static_cast<uint8_t>(brightness));
    say("lights: %s\n", std::string(hal::to_string(r)).c_str());
    return r == hal::CanSendResult::kOk ? 0 : kExitFail;
  }

  if (app.got_subcommand(jog)) {
    // Dead-man: commands stream at 50 Hz only while everything is healthy and time remains.
    hal::LinuxClock sleeper;
    listen(driver, clock, 300ms);
    if (nothing_heard(driver)) return no_frames_error(bus_uri);
    const Nanos start = clock.now();
    const Nanos end =
        start + std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(jog_s));
    std::string why = "duration reached";
    Nanos next = start;
    while (true) {
      const Nanos now = clock.now();
      driver.poll(now);
      const auto& s = driver.state();
      if (firmware::tool::interrupted()) {
        why = "interrupted";
      } else if (s.estop()) {
        why = "E-stop";
      } else if (s.stopping_faults() != 0) {
        why = "base fault " + fault_names(s.fault_word);
      } else if (s.rc_has_control()) {
        why = "remote control took over";
      } else if (driver.bus_off()) {
        why = "CAN bus-off";
      } else if (now - start > 300ms && driver.feedback_silent(now)) {
        why = "base feedback silent";
      } else if (now >= end) {
        why = "duration reached";
      } else {
        why.clear();
      }
      if (!why.empty()) break;
      if (now - start >= 300ms || s.in_can_mode()) driver.command(vx, vy, wz, now);
      next += 20ms;
      sleeper.sleep_until(next);
    }
    for (int i = 0; i < 10; ++i) {  // zero, repeated: a lost frame must not leave it moving
      driver.command(0, 0, 0, clock.now());
      sleeper.sleep_until(clock.now() + 20ms);
    }
    listen(driver, clock, 100ms);
    const auto& s = driver.state();
    say("jog stopped: %s; odometry x %+.3f m y %+.3f m theta %+.3f rad; velocity now %.3f m/s\n",
        why.c_str(), s.odom.x_m, s.odom.y_m, s.odom.theta_rad, s.velocity.vx_mps);
    return why == "duration reached" ? 0 : kExitFail;
  }
  return 3;
}

int main(int argc, char** argv) {
  return firmware::tool::main_guarded("companion-candiag", run, argc, argv);
}
