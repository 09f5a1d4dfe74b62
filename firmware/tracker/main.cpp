// companion-tracker: the Amfitrack Gen 3 for people at the robot. Lists the USB devices, streams
// decoded poses with the confidence gate's verdict, records captures (candump-style lines
// `(sec.usec) amfi0 <hex>`) and decodes them (or a raw UART COBS byte stream), and asks the
// devices who they are. --sim uses the built-in simulated tracker instead of a device.
//
//   companion-tracker list
//   companion-tracker --device hid:auto stream --json
//   companion-tracker --device serial:/dev/ttyUSB0 record walk.log --duration-s 60
//   companion-tracker decode walk.log
//   companion-tracker --sim info
#include <fmt/format.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <fstream>
#include <functional>
#include <memory>
#include <numbers>
#include <string>

#include "amfitrack/amfitrack.hpp"
#include "amfitrack/open_link.hpp"
#include "amfitrack/tap_link.hpp"
#include "firmware/tool_console.hpp"
#include "hal/capture/packet_log.hpp"
#include "hal/linux_clock.hpp"
#include "sim/sim_amfitrack.hpp"

namespace {

namespace am = amfitrack;
using firmware::tool::complain;
using firmware::tool::say;
using hal::Nanos;
using namespace std::chrono_literals;

// Exit codes: 0 ok, 1 nothing found / no answer / errors in a file with --strict, 2 cannot open
// the device or file, 3 usage.
constexpr int kExitFail = 1;
constexpr int kExitNoDevice = 2;
constexpr Nanos kPollPeriod = 2ms;  // faster than the 120 Hz frames: no queue builds up

// A live packet source: a device link, or the simulated tracker stepped in the loop.
struct Live {
  std::unique_ptr<sim::SimAmfitrack> sim;
  std::unique_ptr<am::PacketLink> link;
  std::string description;
};

std::optional<Live> open_live(const std::string& device, bool use_sim) {
  Live live;
  if (use_sim) {
    sim::SimAmfitrackConfig sc;
    sc.position_noise_m = 0.002;
    sc.heading_noise_rad = 0.01;
    live.sim = std::make_unique<sim::SimAmfitrack>(sc);
    live.sim->set_sensor_pose(-1.2, 0.3, 0.0, std::numbers::pi);
    live.link = live.sim->host_link();
    live.description = "built-in simulated tracker";
    return live;
  }
  std::string error;
  const auto uri = am::parse_link_uri(device, &error);
  if (!uri) {
    complain("%s\n", error.c_str());
    return std::nullopt;
  }
  am::OpenedLink opened = am::open_link(*uri);
  if (!opened.link) {
    complain("cannot open %s: %s\n", device.c_str(), opened.error.c_str());
    return std::nullopt;
  }
  live.link = std::move(opened.link);
  live.description = opened.description;
  return live;
}

// Runs `each(now)` every poll period until the duration ends, Ctrl-C, or `each` returns false.
void run_loop(Live& live, double duration_s, const std::function<bool(Nanos)>& each) {
  hal::LinuxClock clock;
  const Nanos start = clock.now();
  const Nanos end =
      duration_s > 0
          ? start + std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(duration_s))
          : Nanos::max();
  Nanos next = start;
  while (!firmware::tool::interrupted() && clock.now() < end) {
    const Nanos now = clock.now();
    if (live.sim) live.sim->step(now);
    if (!each(now)) break;
    next += kPollPeriod;
    clock.sleep_until(next);
  }
}

double yaw_deg(const am::SensorMeasurement& m) {
  const auto& q = m.quaternion_xyzw;
  return std::atan2(2 * (q[3] * q[2] + q[0] * q[1]), 1 - 2 * (q[1] * q[1] + q[2] * q[2])) * 180 /
         std::numbers::pi;
}

const char* pose_state_name(uint8_t s) {
  switch (s) {
    case 0:
      return "no-tracking";
    case 1:
      return "tracking";
    case 2:
      return "uncertain";
    default:
      return "starting";
  }
}

std::string measurement_text(const am::SensorMeasurement& m, bool json) {
  if (json) {
    return fmt::format(
        "\"frame_id\":{},\"x_m\":{:.5f},\"y_m\":{:.5f},\"z_m\":{:.5f},\"qx\":{:.6f},\"qy\":{:.6f},"
        "\"qz\":{:.6f},\"qw\":{:.6f},\"yaw_deg\":{:.2f},\"quality\":{},\"pose_state\":\"{}\","
        "\"bfield\":{},\"source_connected\":{},\"rssi\":{},\"gyro_dps\":[{:.2f},{:.2f},{:.2f}]",
        m.frame_id, m.position_m[0], m.position_m[1], m.position_m[2], m.quaternion_xyzw[0],
        m.quaternion_xyzw[1], m.quaternion_xyzw[2], m.quaternion_xyzw[3], yaw_deg(m), m.quality_raw,
        pose_state_name(m.pose_state_raw), static_cast<int>(m.bfield()), m.source_connected(),
        m.rssi, m.gyro_dps[0], m.gyro_dps[1], m.gyro_dps[2]);
  }
  return fmt::format(
      "frame {:>8}  pos {:+.4f} {:+.4f} {:+.4f} m  yaw {:+7.1f} deg  quality {:>3}  {}{}",
      m.frame_id, m.position_m[0], m.position_m[1], m.position_m[2], yaw_deg(m), m.quality_raw,
      pose_state_name(m.pose_state_raw), m.source_connected() ? "" : "  SOURCE DISCONNECTED");
}

std::string packet_text(const am::Packet& p, bool json) {
  const am::ParsedPayload pl = am::decode_payload(p);
  const auto& h = p.header;
  if (!pl.payload) {
    return json ? fmt::format("{{\"tx\":{},\"type\":{},\"error\":\"{}\"}}", h.source,
                              h.payload_type, am::to_string(pl.error))
                : fmt::format("tx {:>3} -> {:>3}  type 0x{:02X}  {} byte(s): {}", h.source,
                              h.destination, h.payload_type, p.payload.size(),
                              am::to_string(pl.error));
  }
  return std::visit(
      [&](const auto& v) -> std::string {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, am::SensorMeasurement>) {
          return json ? fmt::format("{{\"tx\":{},\"type\":\"pose\",{}}}", h.source,
                                    measurement_text(v, true))
                      : fmt::format("tx {:>3}  pose  {}", h.source, measurement_text(v, false));
        } else if constexpr (std::is_same_v<T, am::DeviceIdReply>) {
          return json ? fmt::format(
                            "{{\"tx\":{},\"type\":\"device_id\",\"uuid\":\"{:08X}-{:08X}-"
                            "{:08X}\"}}",
                            h.source, v.uuid[0], v.uuid[1], v.uuid[2])
                      : fmt::format("tx {:>3}  device id  uuid {:08X}-{:08X}-{:08X}", h.source,
                                    v.uuid[0], v.uuid[1], v.uuid[2]);
        } else if constexpr (std::is_same_v<T, am::DeviceNameReply>) {
          return json ? fmt::format("{{\"tx\":{},\"type\":\"name\",\"name\":\"{}\"}}", h.source,
                                    v.name)
                      : fmt::format("tx {:>3}  name  {}", h.source, v.name);
        } else if constexpr (std::is_same_v<T, am::FirmwareVersionReply>) {
          return json ? fmt::format("{{\"tx\":{},\"type\":\"firmware\",\"version\":\"{}\"}}",
                                    h.source, am::firmware_text(v))
                      : fmt::format("tx {:>3}  firmware  {}", h.source, am::firmware_text(v));
        } else if constexpr (std::is_same_v<T, am::ConfigValueReply>) {
          return json ? fmt::format("{{\"tx\":{},\"type\":\"config\",\"uid\":{}}}", h.source, v.uid)
                      : fmt::format("tx {:>3}  config value  uid 0x{:08X} type {} ({} bytes)",
                                    h.source, v.uid, v.type, v.value.size());
        } else if constexpr (std::is_same_v<T, am::StatusReply>) {
          return json ? fmt::format("{{\"tx\":{},\"type\":\"status\",\"code\":{}}}", h.source,
                                    v.code)
                      : fmt::format("tx {:>3}  status 0x{:02X}", h.source, v.code);
        } else {
          return json ? fmt::format("{{\"tx\":{},\"type\":\"source_measurement\",\"bytes\":{}}}",
                                    h.source, v.raw.size())
                      : fmt::format("tx {:>3}  source measurement ({} bytes, layout not public)",
                                    h.source, v.raw.size());
        }
      },
      *pl.payload);
}

// ---- commands ----------------------------------------------------------------------------------

int cmd_list() {
  std::string error;
  const auto devices = am::list_hid_devices(&error);
  if (!error.empty()) {
    complain("%s\n", error.c_str());
    return kExitNoDevice;
  }
  if (devices.empty()) {
    say("no Amfitrack USB devices found (vendor 0x%04X; check the cable, `lsusb`, and the udev "
        "rule for hidraw access)\n",
        am::kUsbVendorId);
    return kExitFail;
  }
  for (const auto& d : devices) {
    say("%-14s %04x:%04x  %-6s  serial %-16s  %s %s\n", d.path.c_str(), d.vendor_id, d.product_id,
        d.product_id == 0x0D01 ? "source" : "sensor", d.serial_number.c_str(),
        d.manufacturer.c_str(), d.product.c_str());
  }
  return 0;
}

int cmd_stream(Live& live, uint8_t sensor, bool json, double duration_s, uint64_t count) {
  am::AmfitrackConfig cfg;
  cfg.sensor_tx_id = sensor;
  am::Amfitrack tracker(*live.link, cfg);
  if (!json) say("streaming TX %u from %s (Ctrl-C stops)\n", sensor, live.description.c_str());
  uint64_t printed = 0;
  Nanos first{0};
  run_loop(live, duration_s, [&](Nanos now) {
    tracker.poll(now);
    for (const auto& sm : tracker.new_measurements()) {
      if (printed == 0) first = sm.stamp;
      const double t = std::chrono::duration<double>(sm.stamp - first).count();
      const auto gate = tracker.confidence(sm.stamp);
      if (json) {
        say("{\"t_s\":%.4f,\"tx\":%u,%s,\"gate\":\"%s\",\"gate_reason\":\"%s\"}\n", t, sensor,
            measurement_text(sm.m, true).c_str(), am::to_string(gate.confidence).data(),
            am::to_string(gate.reason).data());
      } else {
        say("%9.3f s  %s  gate %s%s\n", t, measurement_text(sm.m, false).c_str(),
            am::to_string(gate.confidence).data(),
            gate.reason == am::GateReason::kNone
                ? ""
                : fmt::format(" ({})", am::to_string(gate.reason)).c_str());
      }
      ++printed;
      if (count > 0 && printed >= count) return false;
    }
    (void)std::fflush(stdout);
    return !tracker.link_failed();
  });
  const auto& c = tracker.counters();
  const am::FramingStats fs = live.link->framing_stats();
  uint64_t payload_errors = 0;
  for (uint64_t e : c.payload_errors) {
    payload_errors += e;
  }
  const uint64_t framing_errors = fs.bad_cobs + fs.overlong + fs.bad_packet;
  const std::string summary = fmt::format(
      "frames {} rate {:.1f} Hz dropped {} repeated {} other_tx {} framing_errors {} "
      "payload_errors {}{}",
      c.poses, tracker.rate_hz(), c.dropped_frames, c.repeated_frames, c.poses_other_sensor,
      framing_errors, payload_errors, tracker.link_failed() ? " LINK FAILED" : "");
  if (json) {
    say("{\"summary\":{\"frames\":%llu,\"rate_hz\":%.2f,\"dropped\":%llu,\"repeated\":%llu,"
        "\"framing_errors\":%llu,\"payload_errors\":%llu,\"link_failed\":%s}}\n",
        static_cast<unsigned long long>(c.poses), tracker.rate_hz(),
        static_cast<unsigned long long>(c.dropped_frames),
        static_cast<unsigned long long>(c.repeated_frames),
        static_cast<unsigned long long>(framing_errors),
        static_cast<unsigned long long>(payload_errors), tracker.link_failed() ? "true" : "false");
  } else {
    say("%s\n", summary.c_str());
  }
  if (tracker.link_failed()) return kExitNoDevice;
  return c.poses > 0 ? 0 : kExitFail;
}

int cmd_record(Live& live, const std::string& path, double duration_s) {
  hal::PacketLogWriter writer(path);
  if (!writer.is_open()) {
    complain("cannot write %s\n", path.c_str());
    return kExitNoDevice;
  }
  uint64_t n = 0;
  am::TapLink tap(*live.link, [&](const am::Packet& p) {
    timespec ts{};
    clock_gettime(CLOCK_REALTIME, &ts);  // wall-clock stamps, as candump -l writes
    writer.write({ts.tv_sec, ts.tv_nsec, "amfi0", am::encode_packet(p)});
    ++n;
  });
  // The shell keeps the devices talking (keep-alive) and asks who they are: that is captured too.
  am::Amfitrack tracker(tap, am::AmfitrackConfig{});
  say("recording %s to %s (Ctrl-C stops)\n", live.description.c_str(), path.c_str());
  (void)std::fflush(stdout);
  run_loop(live, duration_s, [&](Nanos now) {
    tracker.poll(now);
    return !tracker.link_failed();
  });
  writer.flush();
  say("recorded %llu packets (%llu poses of TX 2)\n", static_cast<unsigned long long>(n),
      static_cast<unsigned long long>(tracker.counters().poses));
  return tracker.link_failed() ? kExitNoDevice : (n > 0 ? 0 : kExitFail);
}

struct DecodeTally {
  uint64_t packets = 0;
  uint64_t bad_lines = 0;
  std::array<uint64_t, static_cast<size_t>(am::PacketError::kCount)> packet_errors{};
  std::array<uint64_t, static_cast<size_t>(am::PayloadError::kCount)> payload_errors{};
  am::FramingStats cobs;
};

void tally_packet(const am::Packet& p, DecodeTally& t, bool json, const std::string& prefix) {
  ++t.packets;
  const am::ParsedPayload pl = am::decode_payload(p);
  if (!pl.payload) ++t.payload_errors[static_cast<size_t>(pl.error)];
  say("%s%s\n", prefix.c_str(), packet_text(p, json).c_str());
}

int cmd_decode(const std::string& path, bool cobs, bool json, bool strict) {
  DecodeTally t;
  if (cobs) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
      complain("cannot read %s\n", path.c_str());
      return kExitNoDevice;
    }
    am::CobsStreamDecoder dec;
    std::array<char, 4096> buf{};
    while (in.read(buf.data(), buf.size()) || in.gcount() > 0) {
      dec.feed(std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(buf.data()),
                                        static_cast<size_t>(in.gcount())));
      while (auto p = dec.next())
        tally_packet(*p, t, json, "");
    }
    t.cobs = dec.stats();
  } else {
    hal::PacketLogReader reader(path);
    if (!reader.is_open()) {
      complain("cannot read %s\n", path.c_str());
      return kExitNoDevice;
    }
    while (auto rec = reader.next()) {
      const am::ParsedPacket parsed = am::parse_packet(rec->bytes);
      if (!parsed.packet) {
        ++t.packet_errors[static_cast<size_t>(parsed.error)];
        complain("line %llu: %s\n", static_cast<unsigned long long>(reader.line_number()),
                 std::string(am::to_string(parsed.error)).c_str());
        continue;
      }
      const std::string prefix =
          json ? "" : fmt::format("({}.{:06}) {}  ", rec->sec, rec->nsec / 1000, rec->iface);
      tally_packet(*parsed.packet, t, json, prefix);
    }
    t.bad_lines = reader.malformed();
    if (reader.malformed() > 0) complain("%s\n", reader.last_error().c_str());
  }
  for (size_t i = 0; i < t.packet_errors.size(); ++i) {
    t.packet_errors[i] += t.cobs.packet_errors[i];
  }
  std::string errors;
  uint64_t total_errors = t.bad_lines + t.cobs.bad_cobs + t.cobs.overlong;
  auto add = [&](std::string_view what, uint64_t n) {
    if (n == 0) return;
    errors += fmt::format("{}{} {}", errors.empty() ? "" : ", ", n, what);
  };
  add("malformed lines", t.bad_lines);
  add("bad COBS frames", t.cobs.bad_cobs);
  add("overlong garbage runs", t.cobs.overlong);
  for (size_t i = 0; i < t.packet_errors.size(); ++i) {
    add(am::to_string(static_cast<am::PacketError>(i)), t.packet_errors[i]);
    total_errors += t.packet_errors[i];
  }
  for (size_t i = 0; i < t.payload_errors.size(); ++i) {
    add(am::to_string(static_cast<am::PayloadError>(i)), t.payload_errors[i]);
    total_errors += t.payload_errors[i];
  }
  say("%s%llu packets decoded, %llu errors%s%s\n", json ? "# " : "",
      static_cast<unsigned long long>(t.packets), static_cast<unsigned long long>(total_errors),
      errors.empty() ? "" : ": ", errors.c_str());
  return strict && total_errors > 0 ? kExitFail : 0;
}

int cmd_info(Live& live, double timeout_s) {
  am::Amfitrack tracker(*live.link, am::AmfitrackConfig{});
  auto complete = [&] {
    if (tracker.devices().empty()) return false;
    for (const auto& [tx, d] : tracker.devices()) {
      if (d.name.empty() || d.firmware.empty()) return false;
    }
    return true;
  };
  run_loop(live, timeout_s, [&](Nanos now) {
    tracker.poll(now);
    return !complete() && !tracker.link_failed();
  });
  say("%s\n", live.description.c_str());
  for (const auto& [tx, d] : tracker.devices()) {
    say("TX %3u  uuid %08X-%08X-%08X  name %-20s  firmware %s\n", tx, d.uuid[0], d.uuid[1],
        d.uuid[2], d.name.empty() ? "(no answer)" : d.name.c_str(),
        d.firmware.empty() ? "(no answer)" : d.firmware.c_str());
  }
  if (tracker.devices().empty()) {
    say("no device answered RequestDeviceID within %.1f s\n", timeout_s);
    return kExitFail;
  }
  return complete() ? 0 : kExitFail;
}

int run(int argc, char** argv) {
  CLI::App app{"companion-tracker: Amfitrack Gen 3 tool (list, stream, record, decode, info)"};
  app.require_subcommand(1);
  std::string device = "hid:auto";
  bool use_sim = false;
  app.add_option("--device", device,
                 "hid:auto | hid:/dev/hidrawN | hid:serial=<serial> | serial:<port>[@baud]")
      ->capture_default_str();
  app.add_flag("--sim", use_sim, "use the built-in simulated tracker instead of a device");

  app.add_subcommand("list", "list the Amfitrack USB devices (source 0x0D01, sensor 0x0D12)");
  auto* stream = app.add_subcommand("stream", "decoded poses of the sensor, with the gate");
  int sensor = 2;
  bool json = false;
  double duration_s = 0;
  uint64_t count = 0;
  stream->add_option("--sensor", sensor, "TX id of the sensor")->check(CLI::Range(1, 254));
  stream->add_flag("--json", json, "one JSON object per line");
  stream->add_option("--duration-s", duration_s, "stop after this long (0: until Ctrl-C)");
  stream->add_option("--count", count, "stop after this many frames");
  auto* record = app.add_subcommand("record", "write received packets as `(sec.usec) amfi0 <hex>`");
  std::string file;
  record->add_option("file", file, "capture file to write")->required();
  record->add_option("--duration-s", duration_s, "stop after this long (0: until Ctrl-C)");
  auto* decode = app.add_subcommand("decode", "decode a capture file (or a raw COBS stream)");
  bool cobs = false;
  bool strict = false;
  decode->add_option("file", file, "capture file")->required();
  decode->add_flag("--cobs", cobs, "the file is a raw UART byte stream (COBS frames)");
  decode->add_flag("--json", json, "one JSON object per packet");
  decode->add_flag("--strict", strict, "exit 1 when the file has any error");
  auto* info = app.add_subcommand("info", "ask every device for its id, name and firmware");
  double timeout_s = 3.0;
  info->add_option("--timeout-s", timeout_s, "how long to wait for answers")->capture_default_str();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 3;
  }
  firmware::tool::catch_interrupts();

  if (app.got_subcommand("list")) return cmd_list();
  if (app.got_subcommand("decode")) return cmd_decode(file, cobs, json, strict);
  auto live = open_live(device, use_sim);
  if (!live) return kExitNoDevice;
  if (app.got_subcommand("stream")) {
    return cmd_stream(*live, static_cast<uint8_t>(sensor), json, duration_s, count);
  }
  if (app.got_subcommand("record")) return cmd_record(*live, file, duration_s);
  if (app.got_subcommand("info")) return cmd_info(*live, timeout_s);
  return 3;
}

}  // namespace

int main(int argc, char** argv) {
  return firmware::tool::main_guarded("companion-tracker", run, argc, argv);
}
