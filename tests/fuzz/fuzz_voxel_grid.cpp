// libFuzzer: the voxel grid (ray clearing with its walk over empty blocks, marking, the
// seen-through pass, decay) and the costmap built from it, fed rays a scan could carry: finite,
// within 25 m of the robot, placed on a 1/64-cell lattice (so block faces and corners are hit
// exactly) with optional nudges of 1e-9, 1e-12 m or one ulp (nearly parallel to a face). No
// crash, no hang (`make fuzz` runs it with a per-input timeout: a ray along a block face once
// looped for ever, and one along a face past a block's corner again; corpus/along_face_past_corner
// is that input), and the grid stays within its window.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <vector>

#include "core/perception/costmap.hpp"
#include "core/perception/voxel_grid.hpp"

namespace {

constexpr double kCellM = 0.05;
constexpr double kLatticeM = kCellM / 64.0;

double nudge(double v, uint8_t code) {
  switch (code & 7U) {
    case 1:
      return v + 1e-9;
    case 2:
      return v - 1e-9;
    case 3:
      return v + 1e-12;
    case 4:
      return std::nextafter(v, 1e300);
    case 5:
      return std::nextafter(v, -1e300);
    default:
      return v;
  }
}

int16_t read_i16(const uint8_t* p) {
  return static_cast<int16_t>(static_cast<uint16_t>(p[0]) | static_cast<uint16_t>(p[1]) << 8);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static core::VoxelGrid grid = [] {
    core::VoxelGridConfig c;  // the daemon's: 12 m at 5 cm, seen-through on
    c.resolution_m = kCellM;
    return core::VoxelGrid(c);
  }();
  static core::Costmap costmap;
  static int64_t scan = 0;
  if (size < 5) return 0;
  // The robot: anywhere within ~800 m of odom's origin, on the lattice.
  const double rx = read_i16(data) * 0.025;
  const double ry = read_i16(data + 2) * 0.025;
  const bool with_person = (data[4] & 1U) != 0;
  data += 5;
  size -= 5;
  std::vector<core::Ray> rays;
  constexpr size_t kRayBytes = 11;  // origin x, y; end x, y (int16, lattice); z's; flags
  rays.reserve(size / kRayBytes);
  for (; size >= kRayBytes; data += kRayBytes, size -= kRayBytes) {
    const double ox = rx + read_i16(data) * kLatticeM / 16.0;  // the sensor: within 1.6 m
    const double oy = ry + read_i16(data + 2) * kLatticeM / 16.0;
    const double ex = rx + read_i16(data + 4) * kLatticeM;  // within +-25 m
    const double ey = ry + read_i16(data + 6) * kLatticeM;
    const double oz = 0.45 + static_cast<int8_t>(data[8]) * 0.002;
    const double ez = static_cast<int8_t>(data[9]) * 0.02;
    const uint8_t flags = data[10];
    rays.push_back(core::Ray{{nudge(ox, flags), oy, oz},
                             {nudge(ex, flags >> 3), nudge(ey, flags >> 5), ez},
                             (flags & 0x80U) == 0});
  }
  const core::Nanos now{(++scan) * 100'000'000};
  std::optional<core::PersonSweep> person;
  if (with_person) person = core::PersonSweep{{rx + 1.0, ry}, {rx + 1.1, ry + 0.05}};
  grid.recentre(rx, ry);
  grid.insert(rays, core::Pose2{rx, ry, 0.0}, person, now);
  grid.decay(now);
  costmap.build(grid, core::CostmapConfig{}, now);
  const auto cells = static_cast<size_t>(grid.cells_xy()) * static_cast<size_t>(grid.cells_xy());
  if (grid.occupied_count() > cells * static_cast<size_t>(grid.cells_z())) std::abort();
  if (costmap.obstacle_cells() > cells) std::abort();
  return 0;
}
