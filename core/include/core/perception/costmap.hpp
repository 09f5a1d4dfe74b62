#pragma once
// The 2-D costmap the planner and the controller read, projected from the voxel grid and
// inflated with an exact Euclidean distance transform. Scale 0..100 (the paper's R = 30 on it):
//   100  obstacle, or closer than the robot's inscribed radius to one (a collision);
//   99..1  99 * exp(-k (d - r_inscribed)) for an obstacle at distance d (Nav2's shape, rescaled);
//   0    free, or farther than the inflation radius from every obstacle.
// With r_inscribed = 0.35 m and k = 3 /m, cost >= 30 (R, "unsafe") means d < 0.75 m.
// A Costmap is a plain value: built by the lidar task, then published as an immutable snapshot.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/perception/voxel_grid.hpp"
#include "core/util/floor_to_int.hpp"

namespace core {

struct CostmapConfig {
  double inscribed_radius_m = 0.35;
  double inflation_radius_m = 1.2;
  double cost_scaling_per_m = 3.0;  // k
};

inline constexpr uint8_t kCostLethal = 100;

// The cost of a cell at distance d_m from the nearest obstacle (before rounding to a cell value):
// the scale above. The controller uses it to find the cost at which its footprint can touch.
inline double cost_at_distance(const CostmapConfig& config, double d_m) {
  if (d_m <= config.inscribed_radius_m) return kCostLethal;
  if (d_m > config.inflation_radius_m) return 0.0;
  return 99.0 * std::exp(-config.cost_scaling_per_m * (d_m - config.inscribed_radius_m));
}

// The distance from an obstacle below which a cell's cost is at least `cost` (0 < cost < 99):
// the inverse of cost_at_distance (R = 30 -> ~0.75 m with the defaults).
inline double distance_at_cost(const CostmapConfig& config, double cost) {
  const double d = config.inscribed_radius_m + std::log(99.0 / cost) / config.cost_scaling_per_m;
  return std::min(d, config.inflation_radius_m);
}

class Costmap {
 public:
  Costmap() = default;
  Costmap(int cells, double resolution_m);

  // Obstacles = columns of the grid with any occupied voxel in the band; then inflation.
  // Reuses this costmap's buffers (no allocation when the size does not change).
  void build(const VoxelGrid& grid, const CostmapConfig& config, Nanos stamp);

  // Copies the published part (cells, origin, stamp), not the work buffers: what a snapshot needs.
  void copy_cells_from(const Costmap& other);

  [[nodiscard]] int cells() const { return n_; }
  [[nodiscard]] double resolution() const { return res_; }
  [[nodiscard]] double origin_x() const { return ox_; }  // odom, lower corner
  [[nodiscard]] double origin_y() const { return oy_; }
  [[nodiscard]] Nanos stamp() const { return stamp_; }
  // Cell (i, j): x = origin_x + (i + 0.5) res. Outside the map: lethal (unknown is not free).
  [[nodiscard]] uint8_t cell(int i, int j) const {
    if (i < 0 || j < 0 || i >= n_ || j >= n_) return kCostLethal;
    return cost_[static_cast<size_t>(j) * static_cast<size_t>(n_) + static_cast<size_t>(i)];
  }
  // O(1) lookup of the cell containing (x, y) in odom.
  [[nodiscard]] uint8_t at(double x, double y) const;
  // Bilinear interpolation between cell centres (for the controller's smooth cost). Inline: the
  // controller calls it 200 000 times per step.
  [[nodiscard]] double cost(double x, double y) const {
    double gx = 0, gy = 0;
    if (!grid_coordinates(x, y, gx, gy)) return kCostLethal;
    return bilinear(gx, gy);
  }
  // cost(x, y) >= threshold, the same answer, mostly without interpolating (the controller's
  // collision test, 200 000 per step): each quad of four neighbouring cell centres keeps its
  // least and greatest cell, and a bilinear value is a convex combination of its quad's corners,
  // so only a quad whose range straddles the threshold is interpolated. The margin covers the
  // interpolation's rounding (a few ulp of 100), so the answer is exact, not approximately so.
  [[nodiscard]] bool cost_at_least(double x, double y, double threshold) const {
    double gx = 0, gy = 0;
    if (!grid_coordinates(x, y, gx, gy)) return kCostLethal >= threshold;
    const int i = floor_int(gx);
    const int j = floor_int(gy);
    CellRange range{kCostLethal, kCostLethal};  // a quad wholly off the map: every corner lethal
    if (i >= -1 && j >= -1 && i < n_ && j < n_) {
      range = quad_range_[static_cast<size_t>(j + 1) * (static_cast<size_t>(n_) + 1) +
                          static_cast<size_t>(i + 1)];
    }
    if (range.max < threshold - kMargin) return false;
    if (range.min > threshold + kMargin) return true;
    return bilinear(gx, gy) >= threshold;
  }
  [[nodiscard]] const std::vector<uint8_t>& data() const { return cost_; }
  [[nodiscard]] size_t obstacle_cells() const { return obstacles_; }
  // Whether cell (i, j) holds an obstacle itself (a column of occupied voxels; the cost is
  // lethal round it too, out to the inscribed radius). Off the map: false (nothing seen there).
  [[nodiscard]] bool obstacle(int i, int j) const { return obstacle_code(i, j) != 0; }
  // How long cell (i, j) has held an obstacle when the map was built (VoxelGrid::occupied_for_s),
  // in steps of kObstacleAgeStepS up to kObstacleAgeMaxS (older reads as that); 0 where there is
  // none. A walking pedestrian's cells are a fraction of a second old, a wall's as old as it has
  // been in view.
  static constexpr uint32_t kObstacleAgeStepTicks = 5;  // of VoxelGrid::kAgeTickS
  static constexpr double kObstacleAgeStepS = kObstacleAgeStepTicks * VoxelGrid::kAgeTickS;
  static constexpr double kObstacleAgeMaxS = 254 * kObstacleAgeStepS;
  [[nodiscard]] double obstacle_age_s(int i, int j) const {
    const uint8_t code = obstacle_code(i, j);
    return code == 0 ? 0.0 : (code - 1) * kObstacleAgeStepS;
  }
  // An obstacle at least `min_age_s` old in cell (i, j) (one read: the obstacle limit's scan).
  [[nodiscard]] bool obstacle_at_least(int i, int j, double min_age_s) const {
    const uint8_t code = obstacle_code(i, j);
    return code != 0 && (code - 1) * kObstacleAgeStepS >= min_age_s;
  }

 private:
  // Bounds the rounding of a bilinear value (a few ulp of 100) in the range tests.
  static constexpr double kMargin = 1e-9;
  // Grid coordinates of (x, y) between cell centres; false for NaN or far off the map. (A
  // division: multiplying by the inverse resolution is faster but differs in the last bit, which
  // moved a point across a cell edge in 1 of 10 evaluation trials.)
  bool grid_coordinates(double x, double y, double& gx, double& gy) const {
    gx = (x - ox_) / res_ - 0.5;
    gy = (y - oy_) / res_ - 0.5;
    return gx > -1e9 && gx < 1e9 && gy > -1e9 && gy < 1e9;
  }
  [[nodiscard]] double bilinear(double gx, double gy) const {
    const int i = floor_int(gx);
    const int j = floor_int(gy);
    const double fx = gx - i;
    const double fy = gy - j;
    return (1 - fx) * (1 - fy) * cell(i, j) + fx * (1 - fy) * cell(i + 1, j) +
           (1 - fx) * fy * cell(i, j + 1) + fx * fy * cell(i + 1, j + 1);
  }
  // floor() without the libm call (the controller looks the costmap up 200 000 times per step);
  // callers keep |v| < 1e9.
  static int floor_int(double v) { return static_cast<int>(floor_to_int(v)); }
  [[nodiscard]] uint8_t obstacle_code(int i, int j) const {
    if (i < 0 || j < 0 || i >= n_ || j >= n_) return 0;
    return obstacle_[static_cast<size_t>(j) * static_cast<size_t>(n_) + static_cast<size_t>(i)];
  }

  // The least and greatest cost of the four cells of the quad whose lower corner is cell (i, j),
  // i, j in -1 .. n - 1 (cells off the map count as lethal, as cell() has them).
  struct CellRange {
    uint8_t min, max;
  };
  void build_quad_ranges();

  int n_ = 0;
  double res_ = 0.05;
  double ox_ = 0, oy_ = 0;
  Nanos stamp_{0};
  size_t obstacles_ = 0;
  std::vector<uint8_t> cost_;
  // 0: no obstacle; else 1 + the obstacle's age in kObstacleAgeStepS (capped at 254).
  std::vector<uint8_t> obstacle_;
  // (n + 1) x (n + 1), row j + 1, column i + 1 (an empty map: its one quad, all off the map)
  std::vector<CellRange> quad_range_ =
      std::vector<CellRange>(1, CellRange{kCostLethal, kCostLethal});
  // distance transform work buffers
  std::vector<float> dist2_;
  std::vector<uint64_t> row_;      // one grid row's column masks
  std::vector<uint32_t> row_age_;  // and how long each has been occupied (ticks)
  std::vector<float> f_, g_, z_;
  std::vector<int> v_;
  // cost by squared distance in cells, for the configuration it was made for
  std::vector<uint8_t> lut_;
  CostmapConfig lut_config_;
  double lut_res_ = 0;
};

}  // namespace core
