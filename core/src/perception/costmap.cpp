#include "core/perception/costmap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace core {
namespace {

constexpr float kInf = 1e20f;

// Felzenszwalb & Huttenlocher's 1-D squared distance transform of f (n samples) into d.
void edt_1d(const float* f, float* d, int n, int* v, float* z) {
  int k = 0;
  v[0] = 0;
  z[0] = -kInf;
  z[1] = kInf;
  for (int q = 1; q < n; ++q) {
    float s = 0;
    for (;;) {
      const int p = v[k];
      s = ((f[q] + static_cast<float>(q * q)) - (f[p] + static_cast<float>(p * p))) /
          static_cast<float>(2 * q - 2 * p);
      if (s > z[k] || k == 0) break;
      --k;
    }
    if (s <= z[k]) {  // k == 0 and the new parabola dominates everywhere
      v[0] = q;
      z[0] = -kInf;
      z[1] = kInf;
      continue;
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = kInf;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < static_cast<float>(q))
      ++k;
    const float dq = static_cast<float>(q - v[k]);
    d[q] = dq * dq + f[v[k]];
  }
}

}  // namespace

Costmap::Costmap(int cells, double resolution_m)
    : n_(cells),
      res_(resolution_m),
      cost_(static_cast<size_t>(cells) * static_cast<size_t>(cells), 0),
      obstacle_(cost_.size(), 0),
      dist2_(cost_.size(), kInf),
      row_(static_cast<size_t>(cells)),
      row_age_(static_cast<size_t>(cells)),
      f_(static_cast<size_t>(cells)),
      g_(static_cast<size_t>(cells)),
      z_(static_cast<size_t>(cells) + 1),
      v_(static_cast<size_t>(cells)) {
  build_quad_ranges();
}

void Costmap::build(const VoxelGrid& grid, const CostmapConfig& config, Nanos stamp) {
  if (n_ != grid.cells_xy() || res_ != grid.resolution()) {
    *this = Costmap(grid.cells_xy(), grid.resolution());  // only when the grid's size changes
  }
  ox_ = grid.origin_x();
  oy_ = grid.origin_y();
  stamp_ = stamp;
  obstacles_ = 0;
  // Squared distance (in cells) to the nearest obstacle column: rows, then columns. A row or
  // column without an obstacle transforms to kInf everywhere (the parabolas' q^2 vanish in
  // kInf's rounding), so it is filled, not transformed.
  const auto n = static_cast<size_t>(n_);
  for (int j = 0; j < n_; ++j) {
    grid.row(j, row_);
    grid.row_occupied_ticks(j, stamp, row_age_);
    float* out = &dist2_[static_cast<size_t>(j) * n];
    uint8_t* obstacle_out = &obstacle_[static_cast<size_t>(j) * n];
    size_t row_obstacles = 0;
    for (size_t i = 0; i < n; ++i) {
      const bool obstacle = row_[i] != 0;
      row_obstacles += obstacle ? 1U : 0U;
      f_[i] = obstacle ? 0.0f : kInf;
      obstacle_out[i] =
          obstacle ? static_cast<uint8_t>(1 + std::min(row_age_[i] / kObstacleAgeStepTicks, 254U))
                   : 0;
    }
    obstacles_ += row_obstacles;
    if (row_obstacles == 0) {
      std::fill_n(out, n, kInf);
    } else {
      edt_1d(f_.data(), out, n_, v_.data(), z_.data());
    }
  }
  for (int i = 0; i < n_; ++i) {
    bool any = false;
    for (size_t j = 0; j < n; ++j) {
      const float d = dist2_[j * n + static_cast<size_t>(i)];
      f_[j] = d;
      any = any || d < kInf;
    }
    if (!any) continue;  // stays kInf
    edt_1d(f_.data(), g_.data(), n_, v_.data(), z_.data());
    for (int j = 0; j < n_; ++j) {
      dist2_[static_cast<size_t>(j) * static_cast<size_t>(n_) + static_cast<size_t>(i)] =
          g_[static_cast<size_t>(j)];
    }
  }
  // Squared distances between cell centres are integers: the cost of each is tabulated once per
  // configuration (no sqrt/exp per cell).
  const double r_out_cells = config.inflation_radius_m / res_;
  const auto max_d2 = static_cast<size_t>(std::floor(r_out_cells * r_out_cells));
  if (lut_.size() != max_d2 + 1 || lut_res_ != res_ ||
      lut_config_.inscribed_radius_m != config.inscribed_radius_m ||
      lut_config_.inflation_radius_m != config.inflation_radius_m ||
      lut_config_.cost_scaling_per_m != config.cost_scaling_per_m) {
    lut_.resize(max_d2 + 1);
    for (size_t d2 = 0; d2 <= max_d2; ++d2) {
      const double d = std::sqrt(static_cast<double>(d2)) * res_;
      lut_[d2] = d <= config.inscribed_radius_m
                     ? kCostLethal
                     : static_cast<uint8_t>(std::lround(cost_at_distance(config, d)));
    }
    lut_config_ = config;
    lut_res_ = res_;
  }
  const auto limit = static_cast<float>(max_d2);
  for (size_t c = 0; c < cost_.size(); ++c) {
    const float d2 = dist2_[c];
    // d2 holds an exact integer (a sum of squared cell offsets): truncation is exact.
    cost_[c] = d2 <= limit ? lut_[static_cast<size_t>(d2)] : 0;
  }
  build_quad_ranges();
}

void Costmap::build_quad_ranges() {
  // Runs in the lidar task once per costmap (10 Hz; the controller reads it 200 000 times per
  // step): the interior rows straight from the cells, the border (off-map corners) through cell().
  const size_t stride = static_cast<size_t>(n_) + 1;
  quad_range_.resize(stride * stride);
  const auto n = static_cast<size_t>(n_);
  auto generic = [&](int i, int j) {
    const uint8_t a = cell(i, j), b = cell(i + 1, j), c = cell(i, j + 1), d = cell(i + 1, j + 1);
    quad_range_[static_cast<size_t>(j + 1) * stride + static_cast<size_t>(i + 1)] =
        CellRange{std::min({a, b, c, d}), std::max({a, b, c, d})};
  };
  for (int j = -1; j < n_; ++j) {
    const bool interior_row = j >= 0 && j + 1 < n_;
    if (!interior_row) {
      for (int i = -1; i < n_; ++i)
        generic(i, j);
      continue;
    }
    generic(-1, j);
    generic(n_ - 1, j);
    const uint8_t* r0 = &cost_[static_cast<size_t>(j) * n];
    const uint8_t* r1 = r0 + n;
    CellRange* out = &quad_range_[static_cast<size_t>(j + 1) * stride + 1];
    for (size_t i = 0; i + 1 < n; ++i) {
      const uint8_t lo0 = std::min(r0[i], r0[i + 1]), lo1 = std::min(r1[i], r1[i + 1]);
      const uint8_t hi0 = std::max(r0[i], r0[i + 1]), hi1 = std::max(r1[i], r1[i + 1]);
      out[i] = CellRange{std::min(lo0, lo1), std::max(hi0, hi1)};
    }
  }
}

void Costmap::copy_cells_from(const Costmap& other) {
  n_ = other.n_;
  res_ = other.res_;
  ox_ = other.ox_;
  oy_ = other.oy_;
  stamp_ = other.stamp_;
  obstacles_ = other.obstacles_;
  cost_.assign(other.cost_.begin(), other.cost_.end());  // no allocation once sized
  obstacle_.assign(other.obstacle_.begin(), other.obstacle_.end());
  quad_range_.assign(other.quad_range_.begin(), other.quad_range_.end());
}

uint8_t Costmap::at(double x, double y) const {
  const double gx = (x - ox_) / res_;
  const double gy = (y - oy_) / res_;
  if (!(std::abs(gx) < 1e9) || !(std::abs(gy) < 1e9)) return kCostLethal;  // NaN or far away
  return cell(floor_int(gx), floor_int(gy));
}

}  // namespace core
