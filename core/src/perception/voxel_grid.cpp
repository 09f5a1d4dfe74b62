#include "core/perception/voxel_grid.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

#include "core/util/floor_to_int.hpp"

namespace core {
namespace {

constexpr double kNoStep = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;
constexpr double kElevationBinRad = kPi / 180.0;
constexpr int kElevationSearchBins = 3;  // VLP-16 beams are 2 degrees apart

uint16_t stamp_units(Nanos now) {
  return static_cast<uint16_t>((now.count() / 10'000'000) & 0xFFFF);  // 10 ms
}

// 10 ms units, wrapping after 497 days (differences are taken modulo 2^32); never the
// "not occupied" mark itself.
uint32_t since_units(Nanos now) {
  const auto t =
      static_cast<uint32_t>(static_cast<uint64_t>(now.count() / 10'000'000) & 0xFFFFFFFFU);
  return t == 0xFFFFFFFFU ? t - 1 : t;
}

}  // namespace

VoxelGrid::VoxelGrid(const VoxelGridConfig& config)
    : cfg_(config),
      res_(config.resolution_m),
      n_((std::max(kBlock, static_cast<int>(std::lround(config.size_xy_m / config.resolution_m))) +
          kBlock - 1) /
         kBlock * kBlock),
      nz_(std::clamp(
          static_cast<int>(std::ceil((config.z_max_m - config.z_min_m) / config.resolution_m)), 1,
          64)),
      mask_(static_cast<size_t>(n_) * static_cast<size_t>(n_), 0),
      stamp_(mask_.size() * static_cast<size_t>(nz_), 0),
      occupied_since_(mask_.size(), kNotOccupied),
      block_count_(static_cast<size_t>(n_ / kBlock) * static_cast<size_t>(n_ / kBlock), 0),
      traced_(1 << 17),
      depth_(static_cast<size_t>(kAzimuthBins) * kElevationBins, -1.0f),
      azimuth_origin_(kAzimuthBins),
      azimuth_seen_(kAzimuthBins, 0),
      azimuth_bins_(kAzimuthBins),
      elevation_bins_(kElevationBinRad) {}

size_t VoxelGrid::block_of(size_t col) const {
  const size_t i = col % static_cast<size_t>(n_);
  const size_t j = col / static_cast<size_t>(n_);
  return (j / kBlock) * static_cast<size_t>(n_ / kBlock) + i / kBlock;
}

void VoxelGrid::set_column(size_t col, uint64_t mask) {
  const uint64_t old = mask_[col];
  if ((old == 0) != (mask == 0)) {
    uint16_t& c = block_count_[block_of(col)];
    c = mask == 0 ? static_cast<uint16_t>(c - 1) : static_cast<uint16_t>(c + 1);
  }
  mask_[col] = mask;
}

size_t VoxelGrid::slot(int64_t cx, int64_t cy) const {
  const int64_t i = ((cx % n_) + n_) % n_;
  const int64_t j = ((cy % n_) + n_) % n_;
  return static_cast<size_t>(j * n_ + i);
}

void VoxelGrid::empty_column(size_t col) {
  set_column(col, 0);
  occupied_since_[col] = kNotOccupied;
}

void VoxelGrid::recentre(double robot_x_m, double robot_y_m) {
  const int64_t nx = static_cast<int64_t>(std::floor(robot_x_m / res_)) - n_ / 2;
  const int64_t ny = static_cast<int64_t>(std::floor(robot_y_m / res_)) - n_ / 2;
  if (!placed_ || std::abs(nx - ox_) >= n_ || std::abs(ny - oy_) >= n_) {
    std::fill(mask_.begin(), mask_.end(), 0);
    std::fill(block_count_.begin(), block_count_.end(), 0);
    std::fill(occupied_since_.begin(), occupied_since_.end(), kNotOccupied);
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
    for (int64_t cy = oy_; cy < oy_ + n_; ++cy)
      empty_column(slot(x_from + k, cy));
  }
  const int64_t y_from = dy > 0 ? oy_ : oy_ + n_ + dy;
  for (int64_t k = 0; k < std::abs(dy); ++k) {
    for (int64_t cx = ox_; cx < ox_ + n_; ++cx)
      empty_column(slot(cx, y_from + k));
  }
  ox_ = nx;
  oy_ = ny;
}

void VoxelGrid::clear_ray(const Ray& r, int64_t end_cx, int64_t end_cy, int end_cz) {
  // The segment from the origin to the end (shortened to clear_max_range), clipped to the
  // window's box (x, y and the height band); then a 2-D DDA over the columns it crosses. In each
  // column the ray spans a height interval: the layers in it are cleared with one mask
  // operation, so the cost is one step per column, not per voxel.
  const double x0 = r.origin.x, y0 = r.origin.y, z0 = r.origin.z;
  const double dx = r.end.x - x0;
  const double dy = r.end.y - y0;
  const double dz = r.end.z - z0;
  const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (len < 1e-6) return;
  double t1 = 1.0;
  if (len > cfg_.clear_max_range_m) t1 = cfg_.clear_max_range_m / len;
  const double zlo = cfg_.z_min_m;
  const std::array<double, 3> lo = {origin_x(), origin_y(), zlo};
  const std::array<double, 3> hi = {origin_x() + n_ * res_, origin_y() + n_ * res_,
                                    zlo + nz_ * res_};
  const std::array<double, 3> o = {x0, y0, z0};
  const std::array<double, 3> d = {dx, dy, dz};
  double t0 = 0.0;
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
  const double eps = 1e-9;
  const double px = x0 + dx * (t0 + eps);
  const double py = y0 + dy * (t0 + eps);
  const double inv_res = 1.0 / res_;
  int64_t cx = floor_to_int(px * inv_res);
  int64_t cy = floor_to_int(py * inv_res);
  cx = std::clamp<int64_t>(cx, ox_, ox_ + n_ - 1);
  cy = std::clamp<int64_t>(cy, oy_, oy_ + n_ - 1);
  const int sx = dx > 0 ? 1 : -1;
  const int sy = dy > 0 ? 1 : -1;
  const double adx = std::abs(dx);
  const double ady = std::abs(dy);
  double tmx =
      adx < 1e-12 ? kNoStep : (static_cast<double>(cx + (sx > 0 ? 1 : 0)) * res_ - x0) / dx;
  double tmy =
      ady < 1e-12 ? kNoStep : (static_cast<double>(cy + (sy > 0 ? 1 : 0)) * res_ - y0) / dy;
  // Reciprocals once per ray: the loop multiplies (a division costs ~20 cycles).
  const double inv_dx = adx < 1e-12 ? 0.0 : 1.0 / dx;
  const double inv_dy = ady < 1e-12 ? 0.0 : 1.0 / dy;
  const double tdx = adx < 1e-12 ? kNoStep : res_ / adx;
  const double tdy = ady < 1e-12 ? kNoStep : res_ / ady;
  // Storage indices, stepped incrementally (no modulo per step): the window's lower corner is
  // stored at (ox mod n, oy mod n).
  const int64_t si0 = ((ox_ % n_) + n_) % n_;
  const int64_t sj0 = ((oy_ % n_) + n_) % n_;
  auto storage = [&](int64_t c, int64_t corner, int64_t s0) {
    const int64_t s = s0 + (c - corner);
    return s >= n_ ? s - n_ : s;
  };
  int64_t si = storage(cx, ox_, si0);
  int64_t sj = storage(cy, oy_, sj0);
  const double block_m = kBlock * res_;
  const int64_t blocks_per_row = n_ / kBlock;
  // The walk over empty blocks (below) steps block to block only where rounding cannot decide
  // the entry cell: the ray passes a face by eps times its extent across it, which must be well
  // above the rounding of positions this far from odom's origin (~1e-15 of their size), and it
  // crosses the face at least as far from the face's ends.
  const double rounding_m = 1e-13 * (1.0 + std::abs(x0) + std::abs(y0) + adx + ady);
  const bool cross_x_ok = adx * eps > rounding_m;
  const bool cross_y_ok = ady * eps > rounding_m;
  const double corner_margin_m = 4.0 * rounding_m + (adx + ady) * eps * 4.0;
  double t = t0;
  while (t < t1) {
    const auto col = static_cast<size_t>(sj * n_ + si);
    if (block_count_[static_cast<size_t>((sj >> kBlockShift) * blocks_per_row +
                                         (si >> kBlockShift))] == 0) {
      // Nothing to clear in this block: continue from where the ray leaves it.
      const int64_t cx_in = cx, cy_in = cy;
      int64_t bx = cx >> kBlockShift;  // arithmetic shift: floor(cx / kBlock)
      int64_t by = cy >> kBlockShift;
      double t_exit = 0.0;
      bool exit_x = false;  // it leaves the block through an x face
      for (;;) {
        const double tx =
            adx < 1e-12 ? kNoStep
                        : ((static_cast<double>(bx) + (sx > 0 ? 1 : 0)) * block_m - x0) * inv_dx;
        const double ty =
            ady < 1e-12 ? kNoStep
                        : ((static_cast<double>(by) + (sy > 0 ? 1 : 0)) * block_m - y0) * inv_dy;
        t_exit = std::min(tx, ty);
        exit_x = !(ty < tx);  // std::min's choice
        if (t_exit >= t1) return;
        // The block it enters, when the entry cell computed below certainly lies in it (the ray
        // crosses the face away from the corners, and past the face by more than rounding), the
        // block lies wholly in the window and it is empty too: on to its exit without that
        // computation. Otherwise (or for the first block with something in it) the entry cell is
        // computed below, exactly as for every block when the walk is off.
        if (!block_walk_) break;
        const bool via_x = tx < ty;  // (a tie is a corner: the general entry)
        if (!(via_x ? cross_x_ok : cross_y_ok)) break;
        const double along = via_x ? y0 + dy * tx : x0 + dx * ty;  // the other coordinate there
        const double face_lo = static_cast<double>(via_x ? by : bx) * block_m;
        if (!(std::min(along - face_lo, face_lo + block_m - along) > corner_margin_m)) break;
        const int64_t nbx = via_x ? bx + sx : bx;
        const int64_t nby = via_x ? by : by + sy;
        const int64_t first_cx = nbx * kBlock, first_cy = nby * kBlock;
        if (first_cx < ox_ || first_cx + kBlock > ox_ + n_ || first_cy < oy_ ||
            first_cy + kBlock > oy_ + n_) {
          break;
        }
        const int64_t bsi = storage(first_cx, ox_, si0) >> kBlockShift;
        const int64_t bsj = storage(first_cy, oy_, sj0) >> kBlockShift;
        if (block_count_[static_cast<size_t>(bsj * blocks_per_row + bsi)] != 0) break;
        bx = nbx;
        by = nby;
      }
      // Never back along the ray: at a block's corner rounding can put its exit a hair before
      // where it entered, and the cell computed there across a face it has already crossed.
      // Stepping back there walked the same three blocks round a corner for ever (a hang of the
      // lidar task, fuzz_voxel_grid): t and the cell only move the way the ray goes.
      t = std::max(t, t_exit);
      const double qx = x0 + dx * (t + eps);
      const double qy = y0 + dy * (t + eps);
      cx = floor_to_int(qx * inv_res);
      cy = floor_to_int(qy * inv_res);
      cx = sx > 0 ? std::max(cx, cx_in) : std::min(cx, cx_in);
      cy = sy > 0 ? std::max(cy, cy_in) : std::min(cy, cy_in);
      if ((cx >> kBlockShift) == bx && (cy >> kBlockShift) == by) {
        // Still in the block it leaves: its move past the face (eps times its extent across it)
        // is below the rounding of its position (a ray along a block face, nearly parallel to
        // it). Across the face by hand, or it would re-enter here for ever (it did: a hang).
        if (exit_x) {
          cx = sx > 0 ? (bx + 1) * kBlock : bx * kBlock - 1;
        } else {
          cy = sy > 0 ? (by + 1) * kBlock : by * kBlock - 1;
        }
      }
      if (cx < ox_ || cx >= ox_ + n_ || cy < oy_ || cy >= oy_ + n_) break;
      si = storage(cx, ox_, si0);
      sj = storage(cy, oy_, sj0);
      tmx =
          adx < 1e-12 ? kNoStep : (static_cast<double>(cx + (sx > 0 ? 1 : 0)) * res_ - x0) * inv_dx;
      tmy =
          ady < 1e-12 ? kNoStep : (static_cast<double>(cy + (sy > 0 ? 1 : 0)) * res_ - y0) * inv_dy;
      continue;
    }
    const double t_next = std::min(std::min(tmx, tmy), t1);
    const uint64_t m = mask_[col];
    if (m != 0) {
      const double za = (z0 + dz * t - zlo) * inv_res;
      const double zb = (z0 + dz * t_next - zlo) * inv_res;
      const int l0 =
          static_cast<int>(std::clamp<int64_t>(floor_to_int(std::min(za, zb)), 0, nz_ - 1));
      const int l1 =
          static_cast<int>(std::clamp<int64_t>(floor_to_int(std::max(za, zb)), 0, nz_ - 1));
      uint64_t bits =
          (l1 == 63 ? ~uint64_t{0} : ((uint64_t{1} << (l1 + 1)) - 1)) & ~((uint64_t{1} << l0) - 1);
      if (cx == end_cx && cy == end_cy && end_cz >= 0 && end_cz < nz_) {
        bits &= ~(uint64_t{1} << end_cz);  // never clear the hit itself
      }
      const uint64_t hit = m & bits;
      if (hit != 0) {
        stats_.cleared += static_cast<uint64_t>(std::popcount(hit));
        set_column(col, m & ~bits);
      }
    }
    if (t_next >= t1) break;
    t = t_next;
    // Branch-free step (the x-or-y choice is unpredictable): selects instead of jumps.
    const int64_t step_x = tmx <= tmy ? 1 : 0;
    const int64_t step_y = 1 - step_x;
    tmx += step_x != 0 ? tdx : 0.0;
    tmy += step_y != 0 ? tdy : 0.0;
    cx += step_x * sx;
    cy += step_y * sy;
    si += step_x * sx;
    sj += step_y * sy;
    si = si == n_ ? 0 : (si < 0 ? n_ - 1 : si);
    sj = sj == n_ ? 0 : (sj < 0 ? n_ - 1 : sj);
    if (cx < ox_ || cx >= ox_ + n_ || cy < oy_ || cy >= oy_ + n_) break;
  }
}

void VoxelGrid::insert(std::span<const Ray> rays, const Pose2& robot,
                       std::optional<PersonSweep> person, Nanos now) {
  // Clear with every ray first, then mark: a grazing ray of this scan must not erase a return
  // of the same scan.
  ++scan_serial_;
  const size_t table_mask = traced_.size() - 1;
  // The end voxel and its table slot, computed kAhead rays early so that the slot's cache line is
  // fetched while the rays before it are traced (the table is larger than the caches: each probe
  // was a miss).
  struct EndVoxel {
    int64_t cx, cy;
    int cz;
    uint64_t key;
    size_t slot;
  };
  auto end_voxel = [&](const Ray& r) {
    EndVoxel e{};
    e.cx = floor_to_int(r.end.x / res_);
    e.cy = floor_to_int(r.end.y / res_);
    e.cz = static_cast<int>(floor_to_int((r.end.z - cfg_.z_min_m) / res_));
    // One ray per end voxel and scan (a table stamped with the scan's serial: no clearing pass).
    e.key = (static_cast<uint64_t>(e.cx) & 0x1FFFFF) |
            (static_cast<uint64_t>(e.cy) & 0x1FFFFF) << 21 |
            (static_cast<uint64_t>(e.cz + 1024) & 0x1FFFFF) << 42;
    e.slot = static_cast<size_t>((e.key * 0x9E3779B97F4A7C15ULL) >> 40) & table_mask;
    return e;
  };
  constexpr size_t kAhead = 8;
  std::array<EndVoxel, kAhead> ahead{};
  for (size_t i = 0; i < std::min(kAhead, rays.size()); ++i) {
    ahead[i] = end_voxel(rays[i]);
    __builtin_prefetch(&traced_[ahead[i].slot]);
  }
  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    const EndVoxel e = ahead[i % kAhead];
    if (i + kAhead < rays.size()) {
      ahead[i % kAhead] = end_voxel(rays[i + kAhead]);
      __builtin_prefetch(&traced_[ahead[i % kAhead].slot]);
    }
    const int64_t cx = e.cx, cy = e.cy;
    const int cz = e.cz;
    const uint64_t key = e.key;
    size_t h = e.slot;
    bool seen = false;
    for (size_t probe = 0; probe < 8; ++probe, h = (h + 1) & table_mask) {
      TracedSlot& slot = traced_[h];
      if (slot.scan != scan_serial_) {
        slot.scan = scan_serial_;
        slot.key = key;
        break;
      }
      if (slot.key == key) {
        seen = true;
        break;
      }
    }
    if (seen) continue;
    ++stats_.rays_traced;
    // A beam without a return keeps nothing at its end: it clears the whole way.
    clear_ray(r, cx, cy, r.hit ? cz : -1);
  }
  const Pose2 odom_to_base = robot.inverse();
  const uint16_t stamp = stamp_units(now);
  const double r2 = cfg_.person_mask_radius_m * cfg_.person_mask_radius_m;
  // The segment the person swept during the scan (from -> to), once per scan.
  const double sx = person ? person->to.x_m - person->from.x_m : 0.0;
  const double sy = person ? person->to.y_m - person->from.y_m : 0.0;
  const double len2 = sx * sx + sy * sy;
  for (const Ray& r : rays) {
    ++stats_.rays;
    if (!r.hit) {
      ++stats_.no_return;
      continue;
    }
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
      // Distance to the swept segment.
      double ex = r.end.x - person->from.x_m;
      double ey = r.end.y - person->from.y_m;
      if (len2 > 1e-12) {
        const double u = std::clamp((ex * sx + ey * sy) / len2, 0.0, 1.0);
        ex -= u * sx;
        ey -= u * sy;
      }
      if (ex * ex + ey * ey <= r2) {
        ++stats_.person_masked;
        continue;
      }
    }
    const int64_t cx = floor_to_int(r.end.x / res_);
    const int64_t cy = floor_to_int(r.end.y / res_);
    if (cx < ox_ || cx >= ox_ + n_ || cy < oy_ || cy >= oy_ + n_) {
      ++stats_.out_of_window;
      continue;
    }
    const int cz = static_cast<int>(floor_to_int((r.end.z - cfg_.z_min_m) / res_));
    const size_t col = slot(cx, cy);
    set_column(col, mask_[col] | uint64_t{1} << cz);
    stamp_[col * static_cast<size_t>(nz_) + static_cast<size_t>(cz)] = stamp;
    ++stats_.marked;
  }
  if (cfg_.clear_seen_through) clear_seen_through(rays, stamp);
  if (person) clear_person(*person);
  update_occupied_since(now);
}

void VoxelGrid::update_occupied_since(Nanos now) {
  const uint32_t t = since_units(now);
  for (size_t col = 0; col < mask_.size(); ++col) {
    uint32_t& since = occupied_since_[col];
    if (mask_[col] == 0) {
      since = kNotOccupied;
    } else if (since == kNotOccupied) {
      since = t;
    }
  }
}

// Where the tracked person stands, nothing else can: the voxels there are freed. The robot
// following someone sees little past them, and what a pedestrian left there (unseen in the
// person's shadow, so neither ray-cleared nor seen through) would otherwise be an obstacle the
// person walks into, closing their interactive space around them.
void VoxelGrid::clear_person(const PersonSweep& person) {
  const double r = cfg_.person_mask_radius_m;
  const double sx = person.to.x_m - person.from.x_m;
  const double sy = person.to.y_m - person.from.y_m;
  const double len2 = sx * sx + sy * sy;
  const int64_t x0 = floor_to_int((std::min(person.from.x_m, person.to.x_m) - r) / res_);
  const int64_t x1 = floor_to_int((std::max(person.from.x_m, person.to.x_m) + r) / res_);
  const int64_t y0 = floor_to_int((std::min(person.from.y_m, person.to.y_m) - r) / res_);
  const int64_t y1 = floor_to_int((std::max(person.from.y_m, person.to.y_m) + r) / res_);
  for (int64_t cy = std::max(y0, oy_); cy <= std::min(y1, oy_ + n_ - 1); ++cy) {
    for (int64_t cx = std::max(x0, ox_); cx <= std::min(x1, ox_ + n_ - 1); ++cx) {
      const size_t col = slot(cx, cy);
      if (mask_[col] == 0) continue;
      double ex = (static_cast<double>(cx) + 0.5) * res_ - person.from.x_m;
      double ey = (static_cast<double>(cy) + 0.5) * res_ - person.from.y_m;
      if (len2 > 1e-12) {
        const double u = std::clamp((ex * sx + ey * sy) / len2, 0.0, 1.0);
        ex -= u * sx;
        ey -= u * sy;
      }
      if (ex * ex + ey * ey > r * r) continue;
      stats_.person_cleared += static_cast<uint64_t>(std::popcount(mask_[col]));
      set_column(col, 0);
    }
  }
}

// Ray casting frees the voxels a ray crosses, at the heights it crosses them. From a moving robot
// the beams cross a vacated place at other heights than those that marked it, so a walking
// pedestrian left a trail for decay_s: a wall along the path of anyone the robot follows. The
// spatio-temporal voxel layer (which the paper uses) frees what lies in the sensor's frustum and
// was not seen again; this does the same, but occlusion-aware: a voxel is freed only when the
// scan's beams beside it reached beyond it (a voxel behind the person or a wall stays).
void VoxelGrid::clear_seen_through(std::span<const Ray> rays, uint16_t stamp) {
  std::fill(depth_.begin(), depth_.end(), -1.0f);
  std::fill(azimuth_seen_.begin(), azimuth_seen_.end(), 0);
  Point3 mean{};
  size_t used = 0;
  // The returns come firing by firing: a firing's returns share the azimuth bin, and a laser's
  // elevation bin is that of the return a firing (16 returns) before. Those are tried first.
  int azimuth_hint = -1;
  std::array<int64_t, 16> elevation_hint{};
  elevation_hint.fill(std::numeric_limits<int64_t>::min());
  size_t index = 0;
  for (const Ray& r : rays) {
    const double vx = r.end.x - r.origin.x;
    const double vy = r.end.y - r.origin.y;
    const double vz = r.end.z - r.origin.z;
    const double h = std::hypot(vx, vy);
    if (!(h > 1e-6)) continue;
    int64_t& laser_hint = elevation_hint[index++ % elevation_hint.size()];
    laser_hint = elevation_bins_.bin(vz, h, laser_hint);
    const auto ei = static_cast<int>(laser_hint) + kElevationBins / 2;
    if (ei < 0 || ei >= kElevationBins) continue;
    const int ai = azimuth_bins_.bin(vx, vy, azimuth_hint);
    azimuth_hint = ai;
    float& d = depth_[static_cast<size_t>(ai) * kElevationBins + static_cast<size_t>(ei)];
    const auto range = static_cast<float>(std::hypot(h, vz));
    if (azimuth_seen_[static_cast<size_t>(ai)] == 0) {
      azimuth_seen_[static_cast<size_t>(ai)] = 1;
      azimuth_origin_[static_cast<size_t>(ai)] = r.origin;
    }
    d = d < 0.0f ? range : std::min(d, range);
    mean.x += r.origin.x;
    mean.y += r.origin.y;
    mean.z += r.origin.z;
    ++used;
  }
  if (used == 0) return;
  const auto inv = 1.0 / static_cast<double>(used);
  mean = {mean.x * inv, mean.y * inv, mean.z * inv};
  const double reach2 = cfg_.clear_max_range_m * cfg_.clear_max_range_m;
  const auto hidden_max_age = static_cast<uint16_t>(std::min(60000.0, cfg_.hidden_decay_s * 100.0));
  for (int64_t cy = oy_; cy < oy_ + n_; ++cy) {
    for (int64_t cx = ox_; cx < ox_ + n_; ++cx) {
      const size_t col = slot(cx, cy);
      uint64_t m = mask_[col];
      if (m == 0) continue;
      const double x = (static_cast<double>(cx) + 0.5) * res_;
      const double y = (static_cast<double>(cy) + 0.5) * res_;
      if ((x - mean.x) * (x - mean.x) + (y - mean.y) * (y - mean.y) > reach2) continue;
      const ColumnView view = column_view(mean, x, y);
      auto age_of = [&](int k) {
        return static_cast<uint16_t>(
            stamp - stamp_[col * static_cast<size_t>(nz_) + static_cast<size_t>(k)]);
      };
      uint64_t through = 0;
      uint64_t above = 0;
      uint64_t hidden = 0;    // in view behind something, and older than hidden_decay_s
      bool standing = false;  // marked by this scan, or a beam beside a voxel ends at it
      while (m != 0) {
        const int k = std::countr_zero(m);
        m &= m - 1;
        if (age_of(k) == 0) {
          standing = true;
          continue;
        }
        switch (visibility(view, cfg_.z_min_m + (k + 0.5) * res_)) {
          case Visibility::kSeenThrough:
            through |= uint64_t{1} << k;
            break;
          case Visibility::kAboveView:
            above |= uint64_t{1} << k;
            break;
          case Visibility::kHidden:
            // In view but behind something nearer: not seen since it was marked. It fades
            // faster than what is out of view (the frustum acceleration of the spatio-temporal
            // voxel layer): a pedestrian's trail in the followed person's shadow is gone before
            // the robot gets there, while what is really there is marked again when it shows.
            if (age_of(k) > hidden_max_age) hidden |= uint64_t{1} << k;
            break;
          case Visibility::kBlocked:
            standing = true;
            break;
          case Visibility::kUnseen:
            break;
        }
      }
      // What stands on the ground goes with its part in view, above the beams too (a
      // pedestrian's head, once the robot is close enough that the top beam passes below it):
      // every layer of the column up to the top beam must be seen through, or hidden (then the
      // voxels above fade after hidden_decay_s as well).
      uint64_t freed = through | hidden;
      if (!standing && above != 0) {
        bool clear_below = true;
        bool hidden_below = false;
        for (int k = 0; k < nz_ && clear_below; ++k) {
          const Visibility v = visibility(view, cfg_.z_min_m + (k + 0.5) * res_);
          if (v == Visibility::kAboveView) break;
          hidden_below = hidden_below || v == Visibility::kHidden;
          clear_below = v == Visibility::kSeenThrough || v == Visibility::kHidden;
        }
        for (uint64_t a = above; clear_below && a != 0; a &= a - 1) {
          const int k = std::countr_zero(a);
          if (!hidden_below) {
            freed |= uint64_t{1} << k;
          } else if (age_of(k) > hidden_max_age) {
            hidden |= uint64_t{1} << k;
            freed |= uint64_t{1} << k;
          }
        }
      }
      if (freed != 0) {
        stats_.hidden_decayed += static_cast<uint64_t>(std::popcount(hidden));
        stats_.seen_through += static_cast<uint64_t>(std::popcount(freed & ~hidden));
        set_column(col, mask_[col] & ~freed);
      }
    }
  }
}

VoxelGrid::ColumnView VoxelGrid::column_view(const Point3& origin, double x, double y) const {
  // The bin from the scan's mean origin, then again from where the sensor was at that azimuth.
  const Point3& o =
      azimuth_origin_[static_cast<size_t>(azimuth_bins_.bin(x - origin.x, y - origin.y))];
  const double dx = x - o.x, dy = y - o.y;
  return {azimuth_bins_.bin(dx, dy), std::hypot(dx, dy), o.z};
}

VoxelGrid::Visibility VoxelGrid::visibility(const ColumnView& view, double z) const {
  const int ai = view.azimuth_bin;
  const double h = view.horizontal_m;
  const double dz = z - view.sensor_z_m;
  const int64_t elevation_bin = elevation_bins_.bin(dz, h);
  const auto range = static_cast<float>(std::hypot(h, dz));
  const auto margin = static_cast<float>(cfg_.seen_through_margin_m);
  const auto e0 = static_cast<int>(elevation_bin) + kElevationBins / 2;
  // Above the view when the elevation exceeds the top: the bin says so unless the top lies within
  // it (1e-9 rad: far beyond the elevation's rounding), then the angle itself.
  const double view_top = cfg_.view_top_rad + 0.5 * kElevationBinRad;
  const double bin_low = static_cast<double>(elevation_bin) * kElevationBinRad;
  const bool above_view =
      bin_low > view_top + 1e-9 ||
      (bin_low + kElevationBinRad >= view_top - 1e-9 && std::atan2(dz, h) > view_top);
  if (e0 < 0 || (!above_view && e0 >= kElevationBins)) return Visibility::kUnseen;
  // Where did the nearest beams end, at or below the voxel and at or above it (within the beam
  // spacing), in its azimuth bin and the two beside it? Above the sensor's view: the top beam,
  // and whether it passed beyond the column.
  int through = 0, before = 0, beams = 0;
  bool all_found = true;
  auto classify = [&](float end_m, float at_m) {
    ++beams;
    if (end_m > at_m + margin) {
      ++through;
    } else if (end_m < at_m - margin) {
      ++before;
    }
  };
  for (int da = -1; da <= 1; ++da) {
    const int a = (ai + da + kAzimuthBins) % kAzimuthBins;
    const float* column = &depth_[static_cast<size_t>(a) * kElevationBins];
    if (above_view) {
      int top = std::min(e0, kElevationBins - 1);
      while (top >= 0 && column[top] < 0.0f)
        --top;
      if (top < 0) return Visibility::kUnseen;
      const int above_horizon = top - kElevationBins / 2;  // bins
      const double top_el = (above_horizon + 0.5) * kElevationBinRad;
      classify(static_cast<float>(static_cast<double>(column[top]) * std::cos(top_el)),
               static_cast<float>(h));
      continue;
    }
    bool below = false;
    for (int e = e0; e >= 0 && e > e0 - kElevationSearchBins && !below; --e) {
      if (column[e] < 0.0f) continue;
      classify(column[e], range);
      below = true;
    }
    bool above = false;
    for (int e = e0; e < kElevationBins && e < e0 + kElevationSearchBins && !above; ++e) {
      if (column[e] < 0.0f) continue;
      classify(column[e], range);
      above = true;
    }
    all_found = all_found && below && above;
  }
  if (through + before < beams) return Visibility::kBlocked;  // a beam ended at it: it is there
  if (above_view) return Visibility::kAboveView;              // its column's layers in view decide
  if (all_found && through == beams) return Visibility::kSeenThrough;
  if (all_found && before == beams) return Visibility::kHidden;
  return beams > 0 ? Visibility::kBlocked : Visibility::kUnseen;  // partly hidden: an edge
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
      const auto age = static_cast<uint16_t>(
          t - stamp_[col * static_cast<size_t>(nz_) + static_cast<size_t>(k)]);
      if (age > max_age) {
        keep &= ~(uint64_t{1} << k);
        ++stats_.decayed;
      }
    }
    set_column(col, keep);
    if (keep == 0) occupied_since_[col] = kNotOccupied;
  }
}

uint64_t VoxelGrid::column(int i, int j) const {
  return mask_[slot(ox_ + i, oy_ + j)];
}

VoxelGrid::RowRuns VoxelGrid::row_runs(int j) const {
  const auto n = static_cast<size_t>(n_);
  const size_t first = slot(ox_, oy_ + j);  // window column 0 of the row
  return RowRuns{first, first - first % n, n - first % n};
}

void VoxelGrid::row(int j, std::span<uint64_t> out) const {
  const RowRuns r = row_runs(j);
  const auto n = static_cast<size_t>(n_);
  std::copy_n(mask_.begin() + static_cast<std::ptrdiff_t>(r.first), r.wrapped, out.begin());
  std::copy_n(mask_.begin() + static_cast<std::ptrdiff_t>(r.row_start), n - r.wrapped,
              out.begin() + static_cast<std::ptrdiff_t>(r.wrapped));
}

double VoxelGrid::occupied_for_s(int i, int j, Nanos now) const {
  return age_ticks(occupied_since_[slot(ox_ + i, oy_ + j)], since_units(now)) * kAgeTickS;
}

void VoxelGrid::row_occupied_ticks(int j, Nanos now, std::span<uint32_t> ticks) const {
  const RowRuns r = row_runs(j);
  const auto n = static_cast<size_t>(n_);
  const uint32_t t = since_units(now);
  for (size_t i = 0; i < r.wrapped; ++i)
    ticks[i] = age_ticks(occupied_since_[r.first + i], t);
  for (size_t i = r.wrapped; i < n; ++i)
    ticks[i] = age_ticks(occupied_since_[r.row_start + i - r.wrapped], t);
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

size_t VoxelGrid::memory_bytes() const {
  return mask_.capacity() * sizeof(uint64_t) + stamp_.capacity() * sizeof(uint16_t) +
         occupied_since_.capacity() * sizeof(uint32_t) +
         block_count_.capacity() * sizeof(uint16_t) + traced_.capacity() * sizeof(TracedSlot) +
         depth_.capacity() * sizeof(float) + azimuth_origin_.capacity() * sizeof(Point3) +
         azimuth_seen_.capacity();
}

size_t VoxelGrid::occupied_count() const {
  size_t n = 0;
  for (const uint64_t m : mask_)
    n += static_cast<size_t>(std::popcount(m));
  return n;
}

}  // namespace core
