#include "firmware/lidar_pipeline.hpp"

#include <algorithm>
#include <cmath>

namespace firmware {

core::VoxelGridConfig voxel_grid_config(const DaemonConfig& cfg) {
  const auto& c = cfg.costmap;
  core::VoxelGridConfig g;
  g.size_xy_m = c.size_m;
  g.resolution_m = c.resolution_m;
  g.z_min_m = c.z_min_m;
  g.z_max_m = c.z_max_m;
  g.decay_s = c.decay_s;
  g.clear_max_range_m = c.clear_max_range_m;
  g.clear_seen_through = c.clear_seen_through;
  g.hidden_decay_s = c.hidden_decay_s;
  // Above the top beam nothing is seen; a tilted mount raises it on one side (counted everywhere:
  // the conservative way, fewer voxels are taken for out of view).
  const auto& el = vlp16::laser_table(vlp16::Product::kVlp16).elevation_rad;
  g.view_top_rad = *std::max_element(el.begin(), el.end()) + std::abs(cfg.lidar.roll_rad) +
                   std::abs(cfg.lidar.pitch_rad);
  g.footprint_x_min_m = c.footprint_x_min_m;
  g.footprint_x_max_m = c.footprint_x_max_m;
  g.footprint_y_min_m = c.footprint_y_min_m;
  g.footprint_y_max_m = c.footprint_y_max_m;
  g.person_mask_radius_m = c.person_mask_radius_m;
  return g;
}

core::CostmapConfig costmap_config(const DaemonConfig& cfg) {
  return core::CostmapConfig{cfg.costmap.inscribed_radius_m, cfg.costmap.inflation_radius_m,
                             cfg.costmap.cost_scaling_per_m};
}

vlp16::ScanConfig scan_config(const DaemonConfig& cfg) {
  vlp16::ScanConfig s;
  s.cut_azimuth = static_cast<uint16_t>(std::lround(cfg.lidar.cut_azimuth_deg * 100.0) % 36000);
  s.decode.min_range_m = static_cast<float>(cfg.lidar.min_range_m);
  s.decode.max_range_m = static_cast<float>(cfg.lidar.max_range_m);
  // Beams without a return clear free space up to the clearing range (the voxel grid's own
  // limit): otherwise a pedestrian's voxels stay for decay_s wherever no wall stands behind.
  if (cfg.costmap.clear_on_no_return) {
    s.decode.no_return_range_m = static_cast<float>(cfg.costmap.clear_max_range_m);
  }
  return s;
}

vlp16::SensorPose lidar_pose(const DaemonConfig& cfg) {
  return vlp16::SensorPose{{cfg.lidar.x_m, cfg.lidar.y_m, cfg.lidar.z_m},
                           {cfg.lidar.roll_rad, cfg.lidar.pitch_rad, cfg.lidar.yaw_rad}};
}

LidarPipeline::LidarPipeline(const DaemonConfig& cfg)
    : costmap_config_(costmap_config(cfg)),
      assembler_(scan_config(cfg)),
      extrinsics_(lidar_pose(cfg)),
      sensor_origin_{cfg.lidar.x_m, cfg.lidar.y_m, cfg.lidar.z_m},
      grid_(voxel_grid_config(cfg)),
      costmap_(grid_.cells_xy(), grid_.resolution()),
      timed_(scan_config(cfg).max_points),
      rays_(scan_config(cfg).max_points),
      still_(4, core::Nanos::max() / 4) {}

const core::Costmap* LidarPipeline::add_packet(const vlp16::RawDataPacket& packet,
                                               core::Nanos host_stamp,
                                               const core::PoseHistory& odom,
                                               const std::optional<core::HumanTrack>& person) {
  const vlp16::Scan* scan = assembler_.add(packet, host_stamp);
  if (scan == nullptr) return nullptr;
  size_t n = 0;
  for (const vlp16::Point& p : scan->points) {
    if (n >= timed_.size()) break;
    vlp16::Point q = p;
    extrinsics_.apply(q);
    timed_[n++] = core::TimedPoint{q.x_m, q.y_m, q.z_m,
                                   scan->start + core::Nanos(static_cast<int64_t>(
                                                     static_cast<double>(q.time_offset_us) * 1e3)),
                                   !q.no_return};
  }
  // Without odometry (no base) the robot stands at the odom origin.
  const core::PoseHistory* poses = &odom;
  if (odom.size() == 0) {
    still_.add(core::Pose2{}, scan->start - std::chrono::seconds(1));
    poses = &still_;
  }
  const core::DeskewResult d =
      core::deskew(std::span(timed_.data(), n), *poses, sensor_origin_, rays_);
  last_ = ScanReport{n, d.rays, d.no_pose, scan->lost_packets, scan->partial};
  if (n > 0 && d.rays == 0) {
    // Returns but no odometry for any of them (the base is silent): nothing can be placed, and
    // a costmap built anyway would look fresh while it is not. No update.
    ++scans_without_pose_;
    return nullptr;
  }
  const core::Pose2 robot = poses->at(scan->end).value_or(core::Pose2{});
  grid_.recentre(robot.x_m, robot.y_m);
  std::optional<core::PersonSweep> sweep;
  if (person && person->valid) {
    sweep = core::PersonSweep{core::position_at(*person, scan->start),
                              core::position_at(*person, scan->end)};
  }
  grid_.insert(std::span(rays_.data(), d.rays), robot, sweep, scan->end);
  grid_.decay(scan->end);
  costmap_.build(grid_, costmap_config_, scan->end);
  return &costmap_;
}

}  // namespace firmware
