// companion-lidar: the VLP-16 for people. Decodes captures to a table of returns (CSV) or a
// point cloud (PLY) in base_link (the configured extrinsic) or sensor axes, summarises captures
// and live streams (packets, rate, return mode, product, rpm, losses, errors).
//
//   companion-lidar decode walk.pcap > returns.csv
//   companion-lidar decode walk.pcap --format ply --out cloud.ply
//   companion-lidar stats walk.pcap
//   companion-lidar listen --bind udp:0.0.0.0:2368
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <optional>
#include <string>

#include "firmware/config/config_loader.hpp"
#include "firmware/lidar_pipeline.hpp"
#include "firmware/tool_console.hpp"
#include "hal/capture/pcap_file.hpp"
#include "hal/linux_clock.hpp"
#include "hal/net/udp_socket.hpp"
#include "vlp16/extrinsics.hpp"
#include "vlp16/scan_assembler.hpp"
#include "vlp16/vlp16_codec.hpp"

namespace {

using firmware::tool::complain;
using firmware::tool::say;
using namespace std::chrono_literals;

// Exit codes: 0 ok, 1 errors in the data (with --strict) / nothing received, 2 cannot open the
// file, socket or configuration, 3 usage.
constexpr int kExitFail = 1;
constexpr int kExitCannotOpen = 2;

vlp16::SensorPose sensor_pose(const firmware::DaemonConfig& c) {
  return vlp16::SensorPose{{c.lidar.x_m, c.lidar.y_m, c.lidar.z_m},
                           {c.lidar.roll_rad, c.lidar.pitch_rad, c.lidar.yaw_rad}};
}

vlp16::DecodeOptions decode_options(const firmware::DaemonConfig& c) {
  vlp16::DecodeOptions o;
  o.min_range_m = static_cast<float>(c.lidar.min_range_m);
  o.max_range_m = static_cast<float>(c.lidar.max_range_m);
  return o;
}

// Counts of one stream (file or socket): what a technician checks first.
struct StreamStats {
  uint64_t packets = 0;
  uint64_t position_packets = 0;
  std::array<uint64_t, static_cast<size_t>(vlp16::DecodeError::kCount)> errors{};
  std::optional<vlp16::ReturnMode> mode;
  std::optional<vlp16::Product> product;
  bool mixed = false;  // mode or product changed within the stream
  uint64_t lost = 0;
  uint64_t points = 0;
  double first_s = 0, last_s = 0;
  uint64_t azimuth_travel = 0;  // 0.01 degree, summed over packets
  double sensor_span_us = 0;
  std::optional<vlp16::PositionPacket> last_position;

  uint32_t prev_ts = 0;
  uint16_t prev_az = 0;
  bool have_prev = false;

  void add_data(const vlp16::RawDataPacket& p, double capture_s, size_t n_points) {
    if (packets == 0) first_s = capture_s;
    last_s = capture_s;
    ++packets;
    points += n_points;
    if ((mode && *mode != p.mode) || (product && *product != p.product)) mixed = true;
    mode = p.mode;
    product = p.product;
    if (have_prev) {
      const double period = vlp16::ScanAssembler::packet_period_us(p.mode);
      const uint32_t dt = (p.timestamp_us + vlp16::kHourUs - prev_ts) % vlp16::kHourUs;
      if (dt > 1.5 * period) lost += static_cast<uint64_t>(std::lround(dt / period) - 1);
      sensor_span_us += dt;
      azimuth_travel +=
          (p.blocks[0].azimuth + vlp16::kAzimuthUnits - prev_az) % vlp16::kAzimuthUnits;
    }
    have_prev = true;
    prev_ts = p.timestamp_us;
    prev_az = p.blocks[0].azimuth;
  }
  [[nodiscard]] uint64_t error_total() const {
    uint64_t n = 0;
    for (size_t i = 1; i < errors.size(); ++i)
      n += errors[i];
    return n;
  }
  [[nodiscard]] std::string text() const {
    std::string s = fmt::format("data packets {}", packets);
    if (packets > 1 && last_s > first_s) {
      s += fmt::format(" ({:.1f}/s)", static_cast<double>(packets - 1) / (last_s - first_s));
    }
    if (mode) s += fmt::format(", return mode {}", vlp16::to_string(*mode));
    if (product) s += fmt::format(", product {}", vlp16::to_string(*product));
    if (mixed) s += " (CHANGED within the stream)";
    if (sensor_span_us > 0) {
      const double rpm =
          static_cast<double>(azimuth_travel) / 36000.0 / (sensor_span_us * 1e-6) * 60.0;
      s += fmt::format(", {:.0f} rpm", rpm);
    }
    s += fmt::format(", returns {}, lost packets {}, position packets {}", points, lost,
                     position_packets);
    if (last_position) {
      static constexpr std::array<const char*, 4> kPps = {"absent", "synchronizing", "locked",
                                                          "error"};
      s += fmt::format(" (PPS {}{})", kPps[static_cast<size_t>(last_position->pps)],
                       last_position->nmea.empty() ? "" : ", NMEA " + last_position->nmea);
    }
    std::string errs;
    for (size_t i = 1; i < errors.size(); ++i) {
      if (errors[i] == 0) continue;
      errs += fmt::format("{}{} {}", errs.empty() ? "" : ", ", errors[i],
                          vlp16::to_string(static_cast<vlp16::DecodeError>(i)));
    }
    s += fmt::format(", errors {}{}", error_total(), errs.empty() ? "" : " (" + errs + ")");
    return s;
  }
};

int cmd_decode(const std::string& path, const firmware::DaemonConfig& cfg,
               const std::string& format, bool per_packet, bool sensor_frame,
               const std::string& out_path, bool strict) {
  std::string err;
  auto reader = hal::PcapReader::open(path, err);
  if (!reader) {
    complain("%s\n", err.c_str());
    return kExitCannotOpen;
  }
  std::FILE* out = stdout;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(nullptr, &std::fclose);
  if (!out_path.empty()) {
    file.reset(std::fopen(out_path.c_str(), "w"));
    if (!file) {
      complain("cannot write %s\n", out_path.c_str());
      return kExitCannotOpen;
    }
    out = file.get();
  }
  const vlp16::Extrinsics extrinsics(sensor_pose(cfg));
  const vlp16::DecodeOptions options = decode_options(cfg);
  const bool ply = format == "ply";
  std::vector<vlp16::Point> cloud;  // PLY needs the count before the points
  StreamStats st;
  std::array<vlp16::Point, vlp16::kReturnsPerPacket> pts;
  if (!ply) {
    (void)std::fputs(per_packet ? "packet,timestamp_us,mode,product,first_azimuth_deg,"
                                  "last_azimuth_deg,returns\n"
                                : "packet,block,channel,laser,ring,azimuth_deg,distance_m,"
                                  "intensity,x,y,z,time_us\n",
                     out);
  }
  uint64_t index = 0;
  while (auto udp = reader->next(2368)) {
    vlp16::RawDataPacket raw;
    const vlp16::DecodeError e = vlp16::parse_data_packet(udp->payload, raw);
    if (e != vlp16::DecodeError::kNone) {
      ++st.errors[static_cast<size_t>(e)];
      complain("packet %llu: %s\n", static_cast<unsigned long long>(index),
               std::string(vlp16::to_string(e)).c_str());
      ++index;
      continue;
    }
    const size_t n = vlp16::decode_points(raw, options, pts);
    st.add_data(raw, std::chrono::duration<double>(udp->capture_time).count(), n);
    if (per_packet && !ply) {
      (void)std::fprintf(out, "%llu,%u,%s,0x%02X,%.2f,%.2f,%zu\n",
                         static_cast<unsigned long long>(index), raw.timestamp_us,
                         std::string(vlp16::to_string(raw.mode)).c_str(),
                         static_cast<unsigned>(raw.product), raw.blocks[0].azimuth / 100.0,
                         raw.blocks[11].azimuth / 100.0, n);
    }
    for (size_t i = 0; i < n; ++i) {
      vlp16::Point p = pts[i];
      if (!sensor_frame) extrinsics.apply(p);
      if (ply) {
        cloud.push_back(p);
      } else if (!per_packet) {
        (void)std::fprintf(out, "%llu,%u,%u,%u,%u,%.2f,%.3f,%u,%.4f,%.4f,%.4f,%.3f\n",
                           static_cast<unsigned long long>(index), p.block, p.channel, p.laser,
                           p.ring, p.azimuth / 100.0, static_cast<double>(p.distance_m),
                           p.intensity, static_cast<double>(p.x_m), static_cast<double>(p.y_m),
                           static_cast<double>(p.z_m),
                           raw.timestamp_us + static_cast<double>(p.time_offset_us));
      }
    }
    ++index;
  }
  if (ply) {
    (void)std::fprintf(out,
                       "ply\nformat ascii 1.0\ncomment companion-lidar %s (%s frame)\nelement "
                       "vertex %zu\nproperty float x\nproperty float y\nproperty float z\n"
                       "property uchar intensity\nproperty uchar ring\nend_header\n",
                       path.c_str(), sensor_frame ? "sensor" : "base_link", cloud.size());
    for (const auto& p : cloud) {
      (void)std::fprintf(out, "%.4f %.4f %.4f %u %u\n", static_cast<double>(p.x_m),
                         static_cast<double>(p.y_m), static_cast<double>(p.z_m), p.intensity,
                         p.ring);
    }
  }
  complain("%s: %s\n", path.c_str(), st.text().c_str());
  return strict && st.error_total() > 0 ? kExitFail : 0;
}

int cmd_stats(const std::string& path, bool strict) {
  std::string err;
  auto reader = hal::PcapReader::open(path, err);
  if (!reader) {
    complain("%s\n", err.c_str());
    return kExitCannotOpen;
  }
  StreamStats st;
  std::array<vlp16::Point, vlp16::kReturnsPerPacket> pts;
  while (auto udp = reader->next()) {
    if (udp->destination_port == 8308) {
      vlp16::PositionPacket pos;
      if (vlp16::parse_position_packet(udp->payload, pos) == vlp16::DecodeError::kNone) {
        ++st.position_packets;
        st.last_position = pos;
      } else {
        ++st.errors[static_cast<size_t>(vlp16::DecodeError::kWrongSize)];
      }
      continue;
    }
    if (udp->destination_port != 2368) continue;
    vlp16::RawDataPacket raw;
    const vlp16::DecodeError e = vlp16::parse_data_packet(udp->payload, raw);
    if (e != vlp16::DecodeError::kNone) {
      ++st.errors[static_cast<size_t>(e)];
      continue;
    }
    st.add_data(raw, std::chrono::duration<double>(udp->capture_time).count(),
                vlp16::decode_points(raw, {}, pts));
  }
  const auto& ps = reader->stats();
  say("%s\n%s\nframes %llu: udp 2368/8308 %llu, other ports %llu, not udp %llu, fragments %llu, "
      "malformed %llu\n",
      path.c_str(), st.text().c_str(), static_cast<unsigned long long>(ps.frames),
      static_cast<unsigned long long>(ps.udp), static_cast<unsigned long long>(ps.other_port),
      static_cast<unsigned long long>(ps.not_udp), static_cast<unsigned long long>(ps.fragments),
      static_cast<unsigned long long>(ps.malformed));
  return strict && (st.error_total() > 0 || st.lost > 0) ? kExitFail : 0;
}

int cmd_listen(const std::string& bind, double duration_s) {
  hal::UdpEndpoint ep;
  std::string err;
  if (!hal::parse_udp_endpoint(bind, ep, err)) {
    complain("%s\n", err.c_str());
    return kExitCannotOpen;
  }
  auto opened = hal::UdpReceiver::open(ep);
  if (!opened.receiver) {
    complain("%s\n", opened.error.c_str());
    return kExitCannotOpen;
  }
  auto& rx = *opened.receiver;
  say("listening on %s:%u (receive buffer %d bytes); a line per second, Ctrl-C stops\n",
      ep.address.c_str(), rx.port(), rx.buffer_bytes());
  (void)std::fflush(stdout);
  hal::LinuxClock clock;
  const hal::Nanos start = clock.now();
  const hal::Nanos end = duration_s > 0 ? start + std::chrono::duration_cast<hal::Nanos>(
                                                      std::chrono::duration<double>(duration_s))
                                        : hal::Nanos::max();
  StreamStats st;
  std::array<vlp16::Point, vlp16::kReturnsPerPacket> pts;
  hal::Nanos next_line = start + 1s;
  for (hal::Nanos next = start; !firmware::tool::interrupted() && clock.now() < end; next += 5ms) {
    const hal::Nanos now = clock.now();
    rx.drain(1000, now, [&](const hal::UdpDatagram& d) {
      vlp16::RawDataPacket raw;
      const vlp16::DecodeError e = vlp16::parse_data_packet(d.bytes, raw);
      if (e != vlp16::DecodeError::kNone) {
        ++st.errors[static_cast<size_t>(e)];
        return;
      }
      st.add_data(raw, std::chrono::duration<double>(d.stamp).count(),
                  vlp16::decode_points(raw, {}, pts));
    });
    if (now >= next_line) {
      say("%s, kernel drops %llu\n", st.text().c_str(),
          static_cast<unsigned long long>(rx.stats().kernel_drops));
      (void)std::fflush(stdout);
      next_line += 1s;
    }
    clock.sleep_until(next);
  }
  say("total: %s, kernel drops %llu, truncated %llu\n", st.text().c_str(),
      static_cast<unsigned long long>(rx.stats().kernel_drops),
      static_cast<unsigned long long>(rx.stats().truncated));
  return st.packets > 0 ? 0 : kExitFail;
}

// PGM (binary, P5): white = free, black = lethal; north (+y in odom) up, +x to the right.
bool write_pgm(const std::string& path, const core::Costmap& m) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  const int n = m.cells();
  (void)std::fprintf(
      f, "P5\n# companion costmap, 0..100 as 255..0, origin %.3f %.3f, %.3f m/px\n%d %d\n255\n",
      m.origin_x(), m.origin_y(), m.resolution(), n, n);
  std::vector<uint8_t> row(static_cast<size_t>(n));
  for (int j = n - 1; j >= 0; --j) {
    for (int i = 0; i < n; ++i) {
      row[static_cast<size_t>(i)] = static_cast<uint8_t>(255 - m.cell(i, j) * 255 / 100);
    }
    (void)std::fwrite(row.data(), 1, row.size(), f);
  }
  return std::fclose(f) == 0;
}

int cmd_costmap(const std::string& path, const firmware::DaemonConfig& cfg,
                const std::string& out_dir) {
  std::string err;
  auto reader = hal::PcapReader::open(path, err);
  if (!reader) {
    complain("%s\n", err.c_str());
    return kExitCannotOpen;
  }
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) {
    complain("cannot create %s: %s\n", out_dir.c_str(), ec.message().c_str());
    return kExitCannotOpen;
  }
  firmware::LidarPipeline pipeline(cfg);
  const core::PoseHistory no_odometry(1, core::Nanos(0));  // the sensor stands still
  int scans = 0;
  const core::Nanos t0{0};
  while (auto udp = reader->next(2368)) {
    vlp16::RawDataPacket raw;
    if (vlp16::parse_data_packet(udp->payload, raw) != vlp16::DecodeError::kNone) continue;
    // Capture time as the host's reception time (relative to the file's start).
    const core::Costmap* m =
        pipeline.add_packet(raw, udp->capture_time - t0, no_odometry, std::nullopt);
    if (m == nullptr) continue;
    const std::string file = fmt::format("{}/costmap_{:04d}.pgm", out_dir, scans);
    if (!write_pgm(file, *m)) {
      complain("cannot write %s\n", file.c_str());
      return kExitCannotOpen;
    }
    const auto& s = pipeline.last_scan();
    say("%s: scan %d%s, %zu returns, %zu obstacle cells, %zu voxels occupied\n", file.c_str(),
        scans, s.partial ? " (partial)" : "", s.points, m->obstacle_cells(),
        pipeline.grid().occupied_count());
    ++scans;
  }
  if (scans == 0) {
    say("no complete scan in %s (a scan needs a full revolution past the cut angle)\n",
        path.c_str());
    return kExitFail;
  }
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{"companion-lidar: VLP-16 tool (decode, stats, listen)"};
  app.require_subcommand(1);
  std::string config_path;
  app.add_option(
      "--config", config_path,
      "companiond configuration (for the lidar extrinsic and ranges; default: built-in)");
  std::string file;
  std::string format = "csv";
  std::string out;
  bool per_packet = false;
  bool sensor_frame = false;
  bool strict = false;
  auto* decode = app.add_subcommand("decode", "one row per return (CSV) or a PLY point cloud");
  decode->add_option("file", file, "pcap capture")->required();
  decode->add_option("--format", format, "csv or ply")->check(CLI::IsMember({"csv", "ply"}));
  decode->add_flag("--per-packet", per_packet, "one CSV row per packet instead of per return");
  decode->add_flag("--sensor-frame", sensor_frame, "raw sensor axes instead of base_link");
  decode->add_option("--out", out, "write here instead of stdout");
  decode->add_flag("--strict", strict, "exit 1 when a packet does not decode");
  std::string out_dir;
  auto* costmap = app.add_subcommand("costmap", "voxel grid + costmap per scan, as PGM images");
  costmap->add_option("file", file, "pcap capture")->required();
  costmap->add_option("--out", out_dir, "directory for costmap_NNNN.pgm")->required();
  auto* stats = app.add_subcommand("stats", "packets, rate, mode, product, rpm, losses, errors");
  stats->add_option("file", file, "pcap capture")->required();
  stats->add_flag("--strict", strict, "exit 1 on any decode error or lost packet");
  std::string bind = "udp:0.0.0.0:2368";
  double duration_s = 0;
  auto* listen = app.add_subcommand("listen", "live statistics of the sensor's UDP stream");
  listen->add_option("--bind", bind, "udp:<address>:<port>")->capture_default_str();
  listen->add_option("--duration-s", duration_s, "stop after this long (0: until Ctrl-C)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 3;
  }
  firmware::tool::catch_interrupts();
  const firmware::ConfigResult cr = config_path.empty() ? firmware::load_default_config()
                                                        : firmware::load_config_file(config_path);
  if (!cr.ok()) {
    for (const auto& e : cr.errors)
      complain("%s\n", e.to_string().c_str());
    return kExitCannotOpen;
  }
  if (app.got_subcommand("decode")) {
    return cmd_decode(file, *cr.config, format, per_packet, sensor_frame, out, strict);
  }
  if (app.got_subcommand("stats")) return cmd_stats(file, strict);
  if (app.got_subcommand("costmap")) return cmd_costmap(file, *cr.config, out_dir);
  if (app.got_subcommand("listen")) return cmd_listen(bind, duration_s);
  return 3;
}

}  // namespace

int main(int argc, char** argv) {
  return firmware::tool::main_guarded("companion-lidar", run, argc, argv);
}
