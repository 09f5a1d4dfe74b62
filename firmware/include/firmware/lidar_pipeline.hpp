#pragma once
// The lidar path from packets to a costmap, shared by the daemon's lidar task and
// `companion-lidar costmap`: scan assembly -> extrinsic -> deskew with the wheel odometry ->
// rolling voxel grid (recentred on the robot; mark, ray-clear, decay) -> costmap. Time comes in
// with the packets; buffers are allocated once.
#include <optional>
#include <vector>

#include "core/geometry/pose_history.hpp"
#include "core/human/human_ekf.hpp"
#include "core/perception/costmap.hpp"
#include "core/perception/deskew.hpp"
#include "core/perception/voxel_grid.hpp"
#include "firmware/config/daemon_config.hpp"
#include "vlp16/extrinsics.hpp"
#include "vlp16/scan_assembler.hpp"

namespace firmware {

core::VoxelGridConfig voxel_grid_config(const DaemonConfig& cfg);
core::CostmapConfig costmap_config(const DaemonConfig& cfg);
vlp16::ScanConfig scan_config(const DaemonConfig& cfg);
vlp16::SensorPose lidar_pose(const DaemonConfig& cfg);

struct ScanReport {
  size_t points = 0;
  size_t rays = 0;
  size_t no_pose = 0;  // returns without odometry at their time (dropped)
  uint32_t lost_packets = 0;
  bool partial = false;
};

class LidarPipeline {
 public:
  explicit LidarPipeline(const DaemonConfig& cfg);

  // One decoded packet. When it completes a scan, the scan is processed and the new costmap is
  // returned (valid until the next one); otherwise nullptr. `odom` holds base poses in odom
  // (empty: the robot stands at the odom origin); `person` is the tracked person (odom), whose
  // returns are masked where the track puts them over the scan's time.
  const core::Costmap* add_packet(const vlp16::RawDataPacket& packet, core::Nanos host_stamp,
                                  const core::PoseHistory& odom,
                                  const std::optional<core::HumanTrack>& person);

  [[nodiscard]] const vlp16::ScanAssembler& assembler() const { return assembler_; }
  [[nodiscard]] const core::VoxelGrid& grid() const { return grid_; }
  [[nodiscard]] const ScanReport& last_scan() const { return last_; }
  // Scans dropped because no odometry covered their time (the costmap was not updated).
  [[nodiscard]] uint64_t scans_without_pose() const { return scans_without_pose_; }

 private:
  core::CostmapConfig costmap_config_;
  vlp16::ScanAssembler assembler_;
  vlp16::Extrinsics extrinsics_;
  core::Point3 sensor_origin_;
  core::VoxelGrid grid_;
  core::Costmap costmap_;
  std::vector<core::TimedPoint> timed_;
  std::vector<core::Ray> rays_;
  core::PoseHistory still_;  // the odom origin, when there is no odometry
  ScanReport last_;
  uint64_t scans_without_pose_ = 0;
};

}  // namespace firmware
