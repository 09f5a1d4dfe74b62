#include "core/perception/voxel_grid.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

namespace core {
namespace {

constexpr double kNoStep = std::numeric_limits<double>::infinity();

uint16_t stamp_units(Nanos now) {
  return static_cast<uint16_t>((now.count() / 10'000'000) & 0xFFFF);  // 10 ms
}

}  // namespace

VoxelGrid::VoxelGrid(const VoxelGridConfig& config)
    : cfg_(config),
      res_(config.resolution_m),
      n_(std::max(2, static_cast<int>(std::lround(config.size_xy_m / config.resolution_m)))),
      nz_(std::clamp(static_cast<int>(std::ceil((config.z_max_m - config.z_min_m) /
                                                config.resolution_m)),
                     1, 64)),
      mask_(static_cast<size_t>(n_) * static_cast<size_t>(n_), 0),
      stamp_(mask_.size() * static_cast<size_t>(nz_), 0) {}

size_t VoxelGrid::slot(int64_t cx, int64_t cy) const {
  const int64_t i = ((cx % n_) + n_) % n_;
  const int64_t j = ((cy % n_) + n_) % n_;
  return static_cast<size_t>(j * n_ + i);
}

void VoxelGrid::empty_column(size_t col) {
  mask_[col] = 0;
}

void VoxelGrid::recentre(double robot_x_m, double robot_y_m) {
  const int64_t nx = static_cast<int64_t>(std::floor(robot_x_m / res_)) - n_ / 2;
  const int64_t ny = static_cast<int64_t>(std::floor(robot_y_m / res_)) - n_ / 2;
  if (!placed_ || std::abs(nx - ox_) >= n_ || std::abs(ny - oy_) >= n_) {
    std::fill(mask_.begin(), mask_.end(), 0);
    ox_ = nx;
    oy_ = ny;
    placed_ = true;
    return;
  }
  // Columns (odom cells) that leave the window are emptied; their storage is reused by the cells
  // that enter on the other side.
  const int64_t dx = nx - ox_;
  const int64_t dy = ny - oy_;
  const int64_t x_from = dx > 0 ? ox_ : ox_ + n_ + dx;
  for (int64_t k = 0; k < std::abs(dx); ++k) {
    for (int64_t cy = oy_; cy < oy_ + n_; ++cy) empty_column(slot(x_from + k, cy));
  }
  const int64_t y_from = dy > 0 ? oy_ : oy_ + n_ + dy;
  for (int64_t k = 0; k < std::abs(dy); ++k) {
    for (int64_t cx = ox_; cx < ox_ + n_; ++cx) empty_column(slot(cx, y_from + k));
  }
  ox_ = nx;
  oy_ = ny;
}

void VoxelGrid::clear_ray(const Ray& r, int64_t end_cx, int64_t end_cy, int end_cz) {
  // The segment from the origin to the end (shortened to clear_max_range), clipped to the
  // window's box; then a 3-D DDA (Amanatides & Woo) over the voxels it crosses.
  const double x0 = r.origin.x, y0 = r.origin.y, z0 = r.origin.z;
  const double dx = r.end.x - x0;
  const double dy = r.end.y - y0;
  const double dz = r.end.z - z0;
  const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (len < 1e-6) return;
  double t_max_seg = 1.0;
  if (len > cfg_.clear_max_range_m) t_max_seg = cfg_.clear_max_range_m / len;
  const std::array<double, 3> lo = {origin_x(), origin_y(), cfg_.z_min_m};
  const std::array<double, 3> hi = {origin_x() + n_ * res_, origin_y() + n_ * res_,
                                    cfg_.z_min_m + nz_ * res_};
  const std::array<double, 3> o = {x0, y0, z0};
  const std::array<double, 3> d = {dx, dy, dz};
  double t0 = 0.0;
  double t1 = t_max_seg;
  for (size_t a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (o[a] < lo[a] || o[a] >= hi[a]) return;
      continue;
    }
    double ta = (lo[a] - o[a]) / d[a];
    double tb = (hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 >= t1) return;
  }
  // Start a hair inside the box.
  const double eps = 1e-9;
  double px = x0 + dx * (t0 + eps), py = y0 + dy * (t0 + eps), pz = z0 + dz * (t0 + eps);
  int64_t cx = static_cast<int64_t>(std::floor(px / res_));
  int64_t cy = static_cast<int64_t>(std::floor(py / res_));
  int cz = static_cast<int>(std::floor((pz - cfg_.z_min_m) / res_));
  const int sx = dx > 0 ? 1 : -1, sy = dy > 0 ? 1 : -1, sz = dz > 0 ? 1 : -1;
  auto next_boundary = [&](double p, int64_t c, int s, double base) {
    return base + static_cast<double>(c + (s > 0 ? 1 : 0)) * res_ - p;
  };
  double tmx = std::abs(dx) < 1e-12 ? kNoStep : next_boundary(px, cx, sx, 0.0) / dx;
  double tmy = std::abs(dy) < 1e-12 ? kNoStep : next_boundary(py, cy, sy, 0.0) / dy;
  double tmz = std::abs(dz) < 1e-12 ? kNoStep
                                    : next_boundary(pz, cz, sz, cfg_.z_min_m) / dz;
  const double tdx = std::abs(dx) < 1e-12 ? kNoStep : res_ / std::abs(dx);
  const double tdy = std::abs(dy) < 1e-12 ? kNoStep : res_ / std::abs(dy);
  const double tdz = std::abs(dz) < 1e-12 ? kNoStep : res_ / std::abs(dz);
  double t = t0;
  // tm* are measured from the entry point: shift to absolute parameters.
  tmx += t0;
  tmy += t0;
  tmz += t0;
  while (t < t1) {
    if (cx == end_cx && cy == end_cy && cz == end_cz) break;  // never clear the hit itself
    if (cx >= ox_ && cx < ox_ + n_ && cy >= oy_ && cy < oy_ + n_ && cz >= 0 && cz < nz_) {
      uint64_t& m = mask_[slot(cx, cy)];
      const uint64_t bit = uint64_t{1} << cz;
      if ((m & bit) != 0) {
        m &= ~bit;
        ++stats_.cleared;
      }
    }
    if (tmx <= tmy && tmx <= tmz) {
      t = tmx;
      tmx += tdx;
      cx += sx;
    } else if (tmy <= tmz) {
      t = tmy;
      tmy += tdy;
      cy += sy;
    } else {
      t = tmz;
      tmz += tdz;
      cz += sz;
    }
  }
}

void VoxelGrid::insert(std::span<const Ray> rays, const Pose2& robot, std::optional<Point2> person,
                       Nanos now) {
  // Clear with every ray first, then mark: a grazing ray of this scan must not erase a return
  // of the same scan.
  for (const Ray& r : rays) {
    const int64_t cx = static_cast<int64_t>(std::floor(r.end.x / res_));
    const int64_t cy = static_cast<int64_t>(std::floor(r.end.y / res_));
    const int cz = static_cast<int>(std::floor((r.end.z - cfg_.z_min_m) / res_));
    clear_ray(r, cx, cy, cz);
  }
  const Pose2 odom_to_base = robot.inverse();
  const uint16_t stamp = stamp_units(now);
  const double r2 = cfg_.person_mask_radius_m * cfg_.person_mask_radius_m;
  for (const Ray& r : rays) {
    ++stats_.rays;
    if (r.end.z < cfg_.z_min_m || r.end.z >= cfg_.z_min_m + nz_ * res_) {
      ++stats_.out_of_band;
      continue;
    }
    const Point2 b = odom_to_base.apply({r.end.x, r.end.y});
    if (b.x_m >= cfg_.footprint_x_min_m && b.x_m <= cfg_.footprint_x_max_m &&
        b.y_m >= cfg_.footprint_y_min_m && b.y_m <= cfg_.footprint_y_max_m) {
      ++stats_.self_filtered;
      continue;
    }
    if (person) {
      const double ex = r.end.x - person->x_m;
      const double ey = r.end.y - person->y_m;
      if (ex * ex + ey * ey <= r2) {
        ++stats_.person_masked;
        continue;
      }
    }
    const int64_t cx = static_cast<int64_t>(std::floor(r.end.x / res_));
    const int64_t cy = static_cast<int64_t>(std::floor(r.end.y / res_));
    if (cx < ox_ || cx >= ox_ + n_ || cy < oy_ || cy >= oy_ + n_) {
      ++stats_.out_of_window;
      continue;
    }
    const int cz = static_cast<int>(std::floor((r.end.z - cfg_.z_min_m) / res_));
    const size_t col = slot(cx, cy);
    mask_[col] |= uint64_t{1} << cz;
    stamp_[col * static_cast<size_t>(nz_) + static_cast<size_t>(cz)] = stamp;
    ++stats_.marked;
  }
}

void VoxelGrid::decay(Nanos now) {
  const uint16_t t = stamp_units(now);
  const auto max_age = static_cast<uint16_t>(std::min(60000.0, cfg_.decay_s * 100.0));
  for (size_t col = 0; col < mask_.size(); ++col) {
    uint64_t m = mask_[col];
    if (m == 0) continue;
    uint64_t keep = m;
    while (m != 0) {
      const int k = std::countr_zero(m);
      m &= m - 1;
      const auto age = static_cast<uint16_t>(t - stamp_[col * static_cast<size_t>(nz_) +
                                                       static_cast<size_t>(k)]);
      if (age > max_age) {
        keep &= ~(uint64_t{1} << k);
        ++stats_.decayed;
      }
    }
    mask_[col] = keep;
  }
}

uint64_t VoxelGrid::column(int i, int j) const {
  return mask_[slot(ox_ + i, oy_ + j)];
}

bool VoxelGrid::occupied(double x, double y, double z) const {
  const int64_t cx = static_cast<int64_t>(std::floor(x / res_));
  const int64_t cy = static_cast<int64_t>(std::floor(y / res_));
  const int cz = static_cast<int>(std::floor((z - cfg_.z_min_m) / res_));
  if (cx < ox_ || cx >= ox_ + n_ || cy < oy_ || cy >= oy_ + n_ || cz < 0 || cz >= nz_) {
    return false;
  }
  return (mask_[slot(cx, cy)] >> cz & 1U) != 0;
}

size_t VoxelGrid::occupied_count() const {
  size_t n = 0;
  for (const uint64_t m : mask_) n += static_cast<size_t>(std::popcount(m));
  return n;
}

}  // namespace core
