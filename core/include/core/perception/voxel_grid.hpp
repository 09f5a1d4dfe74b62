#pragma once
// A rolling, robot-centred spatio-temporal voxel grid in `odom` (the idea of the
// spatio-temporal voxel layer, on a fixed dense array):
//   - the window (e.g. 12 m x 12 m at 5 cm, in a height band) follows the robot by whole cells;
//     cells are addressed modulo the window size, so moving never reallocates or copies, and the
//     cells that leave the window are emptied;
//   - marking: the end points of the rays (deskewed lidar returns in odom) inside the height band,
//     except inside the robot's footprint (self-filter) and around the tracked person (mask);
//   - clearing: every voxel a ray passes through before its end point is free (3-D DDA from the
//     sensor origin: the same rays that mark, so nothing is marked that cannot be cleared);
//   - decay: a voxel not re-marked for `decay_s` is freed;
//   - age: how long each column has held an obstacle, as the ends of scans saw it (a wall's
//     columns stay occupied for as long as it is in view; a walking pedestrian leaves a column
//     within a fraction of a second), so consumers can tell settled obstacles from moving ones.
// Each column of the window holds a 64-bit occupancy mask (so the height band is at most 64
// voxels) and a per-voxel marking time. Memory is fixed at construction; nothing allocates after.
// The window side is rounded up to a multiple of 16 cells (rays skip empty 16 x 16 blocks).
#include <algorithm>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "core/geometry/pose2.hpp"
#include "core/perception/angle_bins.hpp"
#include "core/time.hpp"

namespace core {

struct VoxelGridConfig {
  double size_xy_m = 12.0;
  double resolution_m = 0.05;
  double z_min_m = 0.05;  // below: ground (not marked; rays still clear above it)
  double z_max_m = 2.0;   // above: overhead (not marked); at most 64 voxels in the band
  double decay_s = 5.0;
  double clear_max_range_m = 10.0;  // rays are cleared up to this far from the sensor
  // A voxel this scan did not mark is freed when the scan's beams next to it (in azimuth, and
  // just above and below it) all reached at least this much farther: it was seen through.
  bool clear_seen_through = true;
  double seen_through_margin_m = 0.15;
  // A voxel in view but hidden behind something nearer is freed after this long (the rest after
  // decay_s).
  double hidden_decay_s = 0.5;
  // The sensor's highest beam above its horizontal (VLP-16: 15 degrees): what is above it is out
  // of view, however near.
  double view_top_rad = 15.0 * 3.14159265358979323846 / 180.0;
  // Self filter: the robot's body in base_link (returns inside are not obstacles).
  double footprint_x_min_m = -0.35, footprint_x_max_m = 0.35;
  double footprint_y_min_m = -0.30, footprint_y_max_m = 0.30;
  double person_mask_radius_m =
      0.45;  // returns this close to the tracked person's sweep: not marked
};

struct Point3 {
  double x = 0, y = 0, z = 0;
};

struct Ray {
  Point3 origin;  // sensor origin at the return's time (odom)
  Point3 end;     // the return (odom)
  // false: no return; `end` is a point on the beam up to which it crossed free space. The ray
  // clears up to there and marks nothing.
  bool hit = true;
};

struct VoxelGridStats {
  uint64_t rays = 0;
  uint64_t marked = 0;
  uint64_t self_filtered = 0;
  uint64_t person_masked = 0;
  uint64_t out_of_band = 0;     // ground / overhead
  uint64_t out_of_window = 0;   // end point outside the window (the ray still clears)
  uint64_t cleared = 0;         // voxels freed by rays
  uint64_t no_return = 0;       // rays of beams without a return (clear only)
  uint64_t rays_traced = 0;     // rays cast for clearing (one per end voxel and scan)
  uint64_t decayed = 0;         // voxels freed by age
  uint64_t seen_through = 0;    // voxels freed because the scan's beams passed beyond them
  uint64_t person_cleared = 0;  // voxels freed where the tracked person stands
  uint64_t hidden_decayed = 0;  // voxels freed after hidden_decay_s behind something nearer
};

// Where the tracked person was while the scan was taken (odom): from the scan's first return to
// its last. A walking person moves up to 0.15 m in one revolution, and the newest track can be
// 100 ms younger than the scan: masking around one position leaves the person's back unmasked,
// and those returns, marked and inflated, would close the interactive space behind them.
struct PersonSweep {
  Point2 from;
  Point2 to;
};

class VoxelGrid {
 public:
  explicit VoxelGrid(const VoxelGridConfig& config);

  // Centres the window on the robot (odom). Cells that leave the window are emptied.
  void recentre(double robot_x_m, double robot_y_m);
  // Marks and clears with one scan's rays. `robot` is the base pose in odom for the self filter
  // (the scan is short: one pose is accurate to a few cm), `person` the tracked person (odom):
  // returns within person_mask_radius_m of the swept segment are not marked, and voxels there
  // are freed (where the person stands, nothing else does).
  void insert(std::span<const Ray> rays, const Pose2& robot, std::optional<PersonSweep> person,
              Nanos now);
  // Frees voxels older than decay_s.
  void decay(Nanos now);

  [[nodiscard]] int cells_xy() const { return n_; }
  [[nodiscard]] int cells_z() const { return nz_; }
  [[nodiscard]] double resolution() const { return res_; }
  // The window's lower corner in odom (metres) and in cells.
  [[nodiscard]] double origin_x() const { return static_cast<double>(ox_) * res_; }
  [[nodiscard]] double origin_y() const { return static_cast<double>(oy_) * res_; }
  // Occupancy mask of the column at window cell (i, j), 0 <= i, j < cells_xy(); bit k = z layer.
  [[nodiscard]] uint64_t column(int i, int j) const;
  // The masks of window row j (0 <= j < cells_xy()), columns i = 0 .. cells_xy() - 1, into out
  // (cells_xy() entries): two contiguous runs of the storage, no wrapping per column.
  void row(int j, std::span<uint64_t> out) const;
  // How long the column at window cell (i, j) has been occupied at `now` (seconds; 0 if empty):
  // since the end of the first scan (insert) that left it occupied after one that left it
  // empty (or emptied it by decay, or a move of the window). A column cleared and marked again
  // within one scan stays as old as it was. Kept in ticks of kAgeTickS.
  static constexpr double kAgeTickS = 0.01;
  [[nodiscard]] double occupied_for_s(int i, int j, Nanos now) const;
  // The same for window row j in ticks (cells_xy() entries): what the costmap reads per build.
  void row_occupied_ticks(int j, Nanos now, std::span<uint32_t> ticks) const;
  [[nodiscard]] bool occupied(double x, double y, double z) const;
  [[nodiscard]] size_t occupied_count() const;
  // Bytes held by the grid's buffers (fixed at construction).
  [[nodiscard]] size_t memory_bytes() const;
  [[nodiscard]] const VoxelGridStats& stats() const { return stats_; }
  // Ray clearing walks over runs of empty blocks without computing each one's entry cell where
  // rounding cannot decide it (on: the default). Off: every block is entered by that general
  // computation, the reference the walk must equal bit for bit (the tests compare the two).
  void use_block_walk(bool on) { block_walk_ = on; }

 private:
  [[nodiscard]] size_t slot(int64_t cx, int64_t cy) const;  // odom cell -> storage column
  void clear_ray(const Ray& r, int64_t end_cx, int64_t end_cy, int end_cz);
  void clear_seen_through(std::span<const Ray> rays, uint16_t stamp);
  void clear_person(const PersonSweep& person);
  // How this scan saw the point (odom) from `origin`: the beams beside it (above and below it)
  // all passed beyond it, one ended at it, all ended before it (hidden), it is above the highest
  // beam there (and the beams below passed beyond), or no beam came near it.
  enum class Visibility { kSeenThrough, kBlocked, kHidden, kAboveView, kUnseen };
  // A column as the scan saw it: its azimuth bin from where the sensor was at that azimuth, and
  // its horizontal distance from there (the same for every voxel of the column).
  struct ColumnView {
    int azimuth_bin = 0;
    double horizontal_m = 0.0;
    double sensor_z_m = 0.0;
  };
  [[nodiscard]] ColumnView column_view(const Point3& origin, double x, double y) const;
  [[nodiscard]] Visibility visibility(const ColumnView& column, double z) const;
  void empty_column(size_t col);
  void set_column(size_t col, uint64_t mask);  // keeps the block counts
  [[nodiscard]] size_t block_of(size_t col) const;

  VoxelGridConfig cfg_;
  double res_;
  int n_;                    // cells per side
  int nz_;                   // layers
  int64_t ox_ = 0, oy_ = 0;  // window lower corner, odom cells
  bool placed_ = false;
  std::vector<uint64_t> mask_;   // per column
  std::vector<uint16_t> stamp_;  // per voxel: marking time, 10 ms units (wraps at 655 s)
  // Per column: when it became occupied, 10 ms units (wraps after 497 days); kNotOccupied while
  // empty. Updated at the end of each insert, so clearing and marking within one scan do not
  // make a standing wall's columns new.
  static constexpr uint32_t kNotOccupied = 0xFFFFFFFFU;
  std::vector<uint32_t> occupied_since_;
  void update_occupied_since(Nanos now);
  // Ticks from `since` to `now_ticks`; 0 while empty, and for a `now` before the mark (a replay
  // restarted reads as just marked, not as 497 days).
  static uint32_t age_ticks(uint32_t since, uint32_t now_ticks) {
    if (since == kNotOccupied) return 0;
    return static_cast<uint32_t>(std::max(0, static_cast<int32_t>(now_ticks - since)));
  }
  // Window row j in the per-column storage: `wrapped` columns from `first`, then the rest of
  // the row from `row_start` (two contiguous runs).
  struct RowRuns {
    size_t first, row_start, wrapped;
  };
  [[nodiscard]] RowRuns row_runs(int j) const;
  // Non-empty columns per block of kBlock x kBlock columns: rays skip empty blocks whole.
  static constexpr int kBlock = 16;  // the ray loop divides by shifting kBlockShift bits
  static constexpr int kBlockShift = 4;
  std::vector<uint16_t> block_count_;
  // End voxels already traced in this scan (open addressing, cleared per insert): rays that end
  // in the same voxel cross the same voxels to within a fraction of one, so one is cast.
  // Key and scan serial side by side: a probe touches one cache line, not two.
  struct TracedSlot {
    uint64_t key = 0;
    uint32_t scan = 0;
  };
  std::vector<TracedSlot> traced_;
  uint32_t scan_serial_ = 0;
  bool block_walk_ = true;
  // The scan's depth image (nearest range per azimuth x elevation bin, < 0: no beam) and the
  // sensor's origin per azimuth bin (it moves during a revolution).
  static constexpr int kAzimuthBins = 720;   // 0.5 degree
  static constexpr int kElevationBins = 90;  // 1 degree, -45..45 degrees
  std::vector<float> depth_;
  std::vector<Point3> azimuth_origin_;
  std::vector<uint8_t> azimuth_seen_;  // this scan has a ray in the bin
  AzimuthBins azimuth_bins_;
  ElevationBins elevation_bins_;
  VoxelGridStats stats_;
};

}  // namespace core
