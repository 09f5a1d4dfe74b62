// The rolling voxel grid (marking, ray clearing, decay, rolling window, filters) and the
// costmap (exact distance transform, the documented 0..100 mapping, lookups).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/perception/costmap.hpp"
#include "core/perception/voxel_grid.hpp"

using core::Nanos;
using core::Point3;
using core::Ray;
using namespace std::chrono_literals;

namespace {

core::VoxelGridConfig small_grid() {
  core::VoxelGridConfig c;
  c.size_xy_m = 8.0;
  c.resolution_m = 0.1;
  c.z_min_m = 0.1;
  c.z_max_m = 2.0;
  c.decay_s = 2.0;
  return c;
}

constexpr Point3 kSensor{0.0, 0.0, 0.5};

Ray ray_to(double x, double y, double z, Point3 origin = kSensor) {
  return Ray{origin, Point3{x, y, z}};
}

TEST(VoxelGrid, MarksReturnsInTheHeightBandOnly) {
  core::VoxelGrid g(small_grid());
  g.recentre(0, 0);
  const std::vector<Ray> rays = {ray_to(2.0, 0.0, 0.5), ray_to(2.0, 1.0, 0.02) /*ground*/,
                                 ray_to(2.0, -1.0, 2.5) /*overhead*/};
  g.insert(rays, {}, std::nullopt, 1s);
  EXPECT_TRUE(g.occupied(2.0, 0.0, 0.5));
  EXPECT_FALSE(g.occupied(2.0, 1.0, 0.02));
  EXPECT_EQ(g.occupied_count(), 1U);
  EXPECT_EQ(g.stats().out_of_band, 2U);
}

TEST(VoxelGrid, RaysClearWhatTheyPassThroughAndNothingElse) {
  core::VoxelGrid g(small_grid());
  g.recentre(0, 0);
  // A person-height obstacle at 2 m and a low box at 3 m.
  g.insert(std::vector<Ray>{ray_to(2.0, 0.0, 0.5), ray_to(3.0, 0.0, 0.15)}, {}, std::nullopt, 1s);
  ASSERT_TRUE(g.occupied(2.0, 0.0, 0.5));
  ASSERT_TRUE(g.occupied(3.0, 0.0, 0.15));
  // The obstacle at 2 m moved away: a ray now passes through it to a wall at 3.5 m, at the same
  // height: it is cleared. The low box is below the ray: it stays.
  g.insert(std::vector<Ray>{ray_to(3.5, 0.0, 0.5)}, {}, std::nullopt, 1100ms);
  EXPECT_FALSE(g.occupied(2.0, 0.0, 0.5));
  EXPECT_TRUE(g.occupied(3.0, 0.0, 0.15));
  EXPECT_TRUE(g.occupied(3.5, 0.0, 0.5));
  EXPECT_GE(g.stats().cleared, 1U);
  // A ray that ends on an occupied voxel does not clear its own end.
  g.insert(std::vector<Ray>{ray_to(3.5, 0.0, 0.5)}, {}, std::nullopt, 1200ms);
  EXPECT_TRUE(g.occupied(3.5, 0.0, 0.5));
}

TEST(VoxelGrid, ClearingIsLimitedToItsRange) {
  auto cfg = small_grid();
  cfg.clear_max_range_m = 1.0;
  core::VoxelGrid g(cfg);
  g.recentre(0, 0);
  g.insert(std::vector<Ray>{ray_to(0.8, 0.0, 0.5), ray_to(2.0, 0.0, 0.5)}, {}, std::nullopt, 1s);
  g.insert(std::vector<Ray>{ray_to(3.0, 0.0, 0.5)}, {}, std::nullopt, 1100ms);
  EXPECT_FALSE(g.occupied(0.8, 0.0, 0.5)) << "within clear_max_range";
  EXPECT_TRUE(g.occupied(2.0, 0.0, 0.5)) << "beyond clear_max_range: kept";
}

TEST(VoxelGrid, VoxelsDecayAndAreFreed) {
  core::VoxelGrid g(small_grid());
  g.recentre(0, 0);
  g.insert(std::vector<Ray>{ray_to(2.0, 0.0, 0.5), ray_to(-2.0, 0.0, 0.5)}, {}, std::nullopt, 1s);
  g.decay(2500ms);
  EXPECT_EQ(g.occupied_count(), 2U);
  // Only one is seen again.
  g.insert(std::vector<Ray>{ray_to(2.0, 0.0, 0.5, Point3{1.0, 0.0, 0.5})}, {}, std::nullopt,
           2600ms);
  g.decay(3100ms);
  EXPECT_EQ(g.occupied_count(), 1U);
  EXPECT_TRUE(g.occupied(2.0, 0.0, 0.5));
  EXPECT_EQ(g.stats().decayed, 1U);
  g.decay(10s);
  EXPECT_EQ(g.occupied_count(), 0U);
}

TEST(VoxelGrid, SelfFilterAndPersonMask) {
  core::VoxelGrid g(small_grid());
  g.recentre(5, 5);
  const core::Pose2 robot{5.0, 5.0, M_PI / 2};  // facing +y in odom
  const core::PersonSweep person{{5.0, 6.2}, {5.0, 6.2}};
  g.insert(std::vector<Ray>{ray_to(5.2, 5.0, 0.3, Point3{5, 5, 0.5}),   // on the robot's body
                            ray_to(5.1, 6.3, 1.0, Point3{5, 5, 0.5}),   // on the person
                            ray_to(7.0, 5.0, 0.5, Point3{5, 5, 0.5})},  // an obstacle
           robot, person, 1s);
  EXPECT_EQ(g.stats().self_filtered, 1U);
  EXPECT_EQ(g.stats().person_masked, 1U);
  EXPECT_EQ(g.occupied_count(), 1U);
  EXPECT_TRUE(g.occupied(7.0, 5.0, 0.5));
}

TEST(VoxelGrid, PersonMaskCoversWhereThePersonWalkedDuringTheScan) {
  // The person walked from (5, 6) to (5, 6.6) while the scan was taken (a fast walker and a
  // track newer than the scan). Their back at the scan's start (5, 5.75) is 0.85 m from where the
  // track puts them now: a mask around that one position would mark it.
  core::VoxelGrid g(small_grid());
  g.recentre(5, 5);
  const core::Pose2 robot{3.0, 3.0, 0.0};
  const core::Point3 origin{3, 3, 0.5};
  g.insert(std::vector<Ray>{ray_to(5.0, 5.75, 1.0, origin),  // their back, at the start
                            ray_to(5.2, 6.3, 1.0, origin),   // their side, half way
                            ray_to(5.0, 6.85, 1.0, origin),  // their front, at the end
                            ray_to(5.0, 7.2, 1.0, origin)},  // 0.6 m ahead of them: not them
           robot, core::PersonSweep{{5.0, 6.0}, {5.0, 6.6}}, 1s);
  EXPECT_EQ(g.stats().person_masked, 3U);
  EXPECT_EQ(g.occupied_count(), 1U);
  EXPECT_TRUE(g.occupied(5.0, 7.2, 1.0));
}

TEST(VoxelGrid, WhereThePersonWalksIsFreedOfWhatWasLeftThere) {
  // Someone stood at (7, 5), then left unseen (in the shadow of the followed person, say); the
  // followed person now walks through that place: it is freed, and nothing 1 m away is.
  core::VoxelGrid g(small_grid());
  g.recentre(5, 5);
  const Point3 origin{5, 5, 0.5};
  g.insert(std::vector<Ray>{ray_to(7.0, 5.0, 0.5, origin), ray_to(7.0, 6.0, 0.5, origin)},
           core::Pose2{5, 5, 0}, std::nullopt, 1s);
  ASSERT_EQ(g.occupied_count(), 2U);
  g.insert(std::vector<Ray>{}, core::Pose2{5, 5, 0}, core::PersonSweep{{6.8, 4.9}, {7.1, 5.0}},
           1100ms);
  EXPECT_FALSE(g.occupied(7.0, 5.0, 0.5));
  EXPECT_TRUE(g.occupied(7.0, 6.0, 0.5));
  EXPECT_EQ(g.stats().person_cleared, 1U);
}

TEST(VoxelGrid, BeamsWithoutAReturnClearTheWholeWayAndMarkNothing) {
  // A pedestrian stood at (7, 5); they walked on and nothing stands behind that place: the beam
  // that hit them now returns nothing. Its no-return ray must clear their voxel (otherwise it
  // stays for decay_s), and mark nothing at its own end.
  core::VoxelGrid g(small_grid());
  g.recentre(5, 5);
  const Point3 origin{5, 5, 0.5};
  g.insert(std::vector<Ray>{ray_to(7.0, 5.0, 0.5, origin)}, core::Pose2{5, 5, 0}, std::nullopt, 1s);
  ASSERT_TRUE(g.occupied(7.0, 5.0, 0.5));
  Ray nothing = ray_to(8.5, 5.0, 0.5, origin);
  nothing.hit = false;
  g.insert(std::vector<Ray>{nothing}, core::Pose2{5, 5, 0}, std::nullopt, 1100ms);
  EXPECT_FALSE(g.occupied(7.0, 5.0, 0.5));
  EXPECT_FALSE(g.occupied(8.5, 5.0, 0.5)) << "the end of a no-return ray is not an obstacle";
  EXPECT_EQ(g.occupied_count(), 0U);
  EXPECT_EQ(g.stats().no_return, 1U);
}

TEST(VoxelGrid, WindowRollsWithTheRobotWithoutMovingObstacles) {
  core::VoxelGrid g(small_grid());  // 8 m window
  g.recentre(0, 0);
  g.insert(std::vector<Ray>{ray_to(3.0, 0.0, 0.5), ray_to(-3.0, 1.0, 0.5)}, {}, std::nullopt, 1s);
  // 2 m forward: the obstacle behind (x = -3) is now 5 m behind, outside the 4 m half-window.
  g.recentre(2.0, 0.0);
  EXPECT_TRUE(g.occupied(3.0, 0.0, 0.5)) << "still at its odom position";
  EXPECT_FALSE(g.occupied(-3.0, 1.0, 0.5));
  EXPECT_EQ(g.occupied_count(), 1U) << "the one that left was emptied";
  // Back again: what left the window does not come back from stale storage.
  g.recentre(0.0, 0.0);
  EXPECT_FALSE(g.occupied(-3.0, 1.0, 0.5));
  EXPECT_EQ(g.occupied_count(), 1U);
  // The reused storage works at the new place.
  g.recentre(2.0, 2.0);
  g.insert(std::vector<Ray>{ray_to(5.5, 5.5, 0.5, Point3{2, 2, 0.5})}, {}, std::nullopt, 2s);
  EXPECT_TRUE(g.occupied(5.5, 5.5, 0.5));
  EXPECT_FALSE(g.occupied(-2.5, -2.5, 0.5)) << "its storage twin (8 m away) is not affected";
  // A jump larger than the window empties everything.
  g.recentre(100.0, 0.0);
  EXPECT_EQ(g.occupied_count(), 0U);
}

// The costmap reads the grid a row at a time: the rows must be the columns in window order
// wherever the rolled window's storage wraps (here in x and in y).
TEST(VoxelGrid, RowsAreTheWindowsColumnsWhereverTheStorageWraps) {
  core::VoxelGrid g(small_grid());
  g.recentre(0, 0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3.9, 3.9);
  std::vector<Ray> rays;
  rays.reserve(300);
  for (int k = 0; k < 300; ++k)
    rays.push_back(ray_to(u(rng), u(rng), 0.5));
  g.insert(rays, {}, std::nullopt, 1s);
  g.recentre(1.35, -2.05);  // wraps the storage in both directions
  // Half as many again a second later: columns of two ages.
  rays.resize(150);
  for (auto& r : rays)
    r = ray_to(1.35 + u(rng), -2.05 + u(rng), 0.5, Point3{1.35, -2.05, 3.0});
  g.insert(rays, {}, std::nullopt, 2s);
  std::vector<uint64_t> row(static_cast<size_t>(g.cells_xy()));
  std::vector<uint32_t> ages(static_cast<size_t>(g.cells_xy()));
  size_t occupied_columns = 0;
  size_t older = 0;
  for (int j = 0; j < g.cells_xy(); ++j) {
    g.row(j, row);
    g.row_occupied_ticks(j, 2500ms, ages);
    for (int i = 0; i < g.cells_xy(); ++i) {
      ASSERT_EQ(row[static_cast<size_t>(i)], g.column(i, j)) << i << "," << j;
      ASSERT_NEAR(ages[static_cast<size_t>(i)] * core::VoxelGrid::kAgeTickS,
                  g.occupied_for_s(i, j, 2500ms), 1e-12)
          << i << "," << j;
      occupied_columns += row[static_cast<size_t>(i)] != 0 ? 1U : 0U;
      older += ages[static_cast<size_t>(i)] > 100U ? 1U : 0U;  // over 1 s
    }
  }
  EXPECT_GT(occupied_columns, 100U);
  EXPECT_GT(older, 50U) << "the first scan's columns, 1.5 s old";
}

// How long a column has held an obstacle (what tells a wall from a passer-by,
// ObstacleSpeedConfig::settled_s): it grows while scans keep the column occupied, a column
// cleared by one ray and marked by another in the same scan keeps its age, and it starts again
// once the column was emptied: by a ray, by decay, by leaving the window (a step, or a jump).
TEST(VoxelGrid, AColumnsAgeGrowsWhileOccupiedAndStartsAgainOnceEmptied) {
  core::VoxelGrid g(small_grid());  // 0.1 m cells, decay 2 s
  g.recentre(0, 0);
  const auto cell = [&](double v) {
    return static_cast<int>(std::floor(v / 0.1)) + g.cells_xy() / 2;
  };
  const int i = cell(2.05);
  const int j = cell(0.05);
  const std::vector<Ray> wall{ray_to(2.05, 0.05, 0.55)};
  const std::vector<Ray> through{ray_to(3.05, 0.05, 0.55)};  // passes through the wall's voxel
  g.insert(wall, {}, std::nullopt, 1s);
  EXPECT_EQ(g.occupied_for_s(i, j, 1s), 0.0);
  EXPECT_NEAR(g.occupied_for_s(i, j, 1500ms), 0.5, 1e-9);
  g.insert(wall, {}, std::nullopt, 1500ms);
  EXPECT_NEAR(g.occupied_for_s(i, j, 1500ms), 0.5, 1e-9) << "seen again: as old as it was";
  const uint64_t cleared = g.stats().cleared;
  g.insert(std::vector<Ray>{through[0], wall[0]}, {}, std::nullopt, 2s);
  ASSERT_GT(g.stats().cleared, cleared) << "the ray through it cleared the voxel";
  ASSERT_NE(g.column(i, j), 0U) << "and the other marked it again";
  EXPECT_NEAR(g.occupied_for_s(i, j, 2s), 1.0, 1e-9) << "cleared and marked in one scan";
  g.insert(through, {}, std::nullopt, 2500ms);
  ASSERT_EQ(g.column(i, j), 0U);
  EXPECT_EQ(g.occupied_for_s(i, j, 2500ms), 0.0) << "empty: no age";
  g.insert(wall, {}, std::nullopt, 3s);
  EXPECT_NEAR(g.occupied_for_s(i, j, 3200ms), 0.2, 1e-9) << "from the scan that marked it again";
  g.decay(5100ms);  // not marked for 2.1 s
  ASSERT_EQ(g.column(i, j), 0U);
  g.insert(wall, {}, std::nullopt, 5200ms);
  EXPECT_EQ(g.occupied_for_s(i, j, 5200ms), 0.0) << "after decay freed it";
  g.insert(wall, {}, std::nullopt, 5500ms);
  g.recentre(7.0, 0.0);  // the window [3, 11) m: the column leaves it
  g.recentre(0.0, 0.0);
  ASSERT_EQ(g.column(i, j), 0U);
  g.insert(wall, {}, std::nullopt, 6s);
  EXPECT_EQ(g.occupied_for_s(i, j, 6s), 0.0) << "after it left the window";
  g.insert(wall, {}, std::nullopt, 6500ms);
  g.recentre(100.0, 0.0);  // a jump: the whole window emptied at once
  g.recentre(0.0, 0.0);
  g.insert(wall, {}, std::nullopt, 7s);
  EXPECT_EQ(g.occupied_for_s(i, j, 7s), 0.0) << "after a jump of the window";
  EXPECT_EQ(g.occupied_for_s(i, j, 6s), 0.0) << "a time before the mark reads as just marked";
}

// A ray that starts on a block's face and runs nearly parallel to it (its move across the face,
// eps times 1e-9 m, is below the rounding of its position) once re-entered the block it was
// leaving for ever: the lidar task hung. It crosses the face and clears on the other side (in
// exact arithmetic it is over the face after 4e-7 of its length).
TEST(VoxelGrid, ARayAlongABlockFaceEndsAndClearsBeyondTheFace) {
  core::VoxelGridConfig c;  // the defaults: 12 m at 5 cm
  c.clear_seen_through = false;
  core::VoxelGrid g(c);
  g.recentre(0.0, 0.0);
  const double face = -3 * 16 * 0.05;  // x of a block face, computed as the grid does
  ASSERT_EQ(face, -3.0 * (16 * 0.05));
  const double y0 = -0.07;
  const Point3 obstacle{face + 0.025, y0 - 3.0, 0.37};  // the cell right of the face
  g.insert(std::vector<Ray>{Ray{{0.0, 0.0, 0.45}, obstacle}}, {}, std::nullopt, 1s);
  ASSERT_TRUE(g.occupied(obstacle.x, obstacle.y, obstacle.z));
  const Ray along{{face, y0, 0.45}, {face + 1e-9, y0 - 5.5, 0.3}, false};
  g.insert(std::vector<Ray>{along}, {}, std::nullopt, 2s);
  EXPECT_FALSE(g.occupied(obstacle.x, obstacle.y, obstacle.z));
}

// fuzz_voxel_grid's find: a ray along a block face (x = -200.8 m, 251 blocks from odom's
// origin), 1e-12 m off it and nearly parallel, passing a block corner (y = 211.2 m). Rounding put
// its exit from one block a hair before its entry, and the cell there across the face it had
// crossed: it walked the same three blocks round the corner for ever (the lidar task hung).
TEST(VoxelGrid, ARayAlongABlockFacePastACornerEnds) {
  core::VoxelGridConfig c;  // the daemon's: 12 m at 5 cm, seen-through on
  core::VoxelGrid g(c);
  g.recentre(-200.8, 211.175);
  const Ray along{{-200.79999999999902, 211.175, 0.488}, {-200.800000001, 236.185937499, 0.1}};
  const Ray across{{-200.79999999999902, 211.175, 0.488}, {-199.3, 212.6, 0.6}};
  g.insert(std::vector<Ray>{along, across}, core::Pose2{-200.8, 211.175, 0.0}, std::nullopt, 1s);
  EXPECT_TRUE(g.occupied(across.end.x, across.end.y, across.end.z)) << "the scan was inserted";
  EXPECT_EQ(g.stats().marked, 1U) << "the return within the window; the other ends beyond it";
}

// Ray clearing walks over runs of empty blocks without computing each entry cell; the grid it
// leaves must equal, bit for bit, the one where every block is entered by the general
// computation: random rays and obstacles (returns and beams without a return, windows rolled to
// odd offsets, near odom's origin and kilometres from it) and the walk's hard cases (rays along
// block faces, through block corners, nearly parallel to an axis).
TEST(VoxelGrid, TheWalkOverEmptyBlocksClearsExactlyWhatTheGeneralEntryDoes) {
  core::VoxelGridConfig c;       // the defaults: 12 m at 5 cm, 0.05-2.0 m, clearing to 10 m
  c.clear_seen_through = false;  // ray clearing alone
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  size_t cleared = 0;
  for (const double far : {0.0, 3.3e3}) {
    core::VoxelGrid walk(c);
    core::VoxelGrid general(c);
    general.use_block_walk(false);
    double rx = far + 0.37, ry = -far * 0.5 + 0.11;
    for (int scan = 0; scan < 12; ++scan) {
      rx += 0.23 * u(rng);
      ry += 0.19 * u(rng);
      walk.recentre(rx, ry);
      general.recentre(rx, ry);
      const Point3 o{rx + 0.1 * u(rng), ry + 0.1 * u(rng), 0.45};
      std::vector<Ray> rays;
      // Obstacles in a few places (people, a post), so most blocks stay empty.
      for (int k = 0; k < 6; ++k) {
        const double cx = rx + 5.0 * u(rng), cy = ry + 5.0 * u(rng);
        for (int p = 0; p < 60; ++p) {
          rays.push_back(Ray{o, {cx + 0.2 * u(rng), cy + 0.2 * u(rng), 1.0 + 0.9 * u(rng)}});
        }
      }
      // Beams in every direction, returns and no-returns, up and down.
      for (int k = 0; k < 3000; ++k) {
        const double a = 3.14159 * u(rng);
        const double range = 0.5 + 9.5 * (0.5 + 0.5 * u(rng));
        rays.push_back(
            Ray{o,
                {o.x + range * std::cos(a), o.y + range * std::sin(a), o.z + range * 0.26 * u(rng)},
                k % 3 != 0});
      }
      // Along block faces, through block corners, nearly axis-parallel.
      const double block_m = 16 * c.resolution_m;
      const double fx = std::floor(rx / block_m) * block_m;
      const double fy = std::floor(ry / block_m) * block_m;
      for (int k = -4; k <= 4; ++k) {
        const Point3 on_face{fx + k * block_m, ry, 0.45};
        rays.push_back(Ray{on_face, {on_face.x, on_face.y + 5.5, 0.3}, false});
        rays.push_back(Ray{on_face, {on_face.x + 1e-9, on_face.y - 5.5, 0.3}, false});
        const Point3 corner{fx + k * block_m, fy - k * block_m, 0.45};
        rays.push_back(Ray{corner, {corner.x + 5.0, corner.y + 5.0, 0.4}, false});
        rays.push_back(Ray{corner, {corner.x - 5.0, corner.y + 5.0 + 1e-12, 0.4}, false});
        rays.push_back(Ray{o, {o.x + 6.0, o.y + 1e-7 * k, 0.5}, false});
      }
      const core::Pose2 robot{rx, ry, 0.0};
      walk.insert(rays, robot, std::nullopt, core::Nanos(std::chrono::seconds(1 + scan)));
      general.insert(rays, robot, std::nullopt, core::Nanos(std::chrono::seconds(1 + scan)));
      for (int j = 0; j < walk.cells_xy(); ++j) {
        for (int i = 0; i < walk.cells_xy(); ++i)
          ASSERT_EQ(walk.column(i, j), general.column(i, j)) << far << " " << scan << " " << i;
      }
      ASSERT_EQ(walk.stats().cleared, general.stats().cleared);
    }
    cleared += walk.stats().cleared;
  }
  EXPECT_GT(cleared, 1000U) << "the rays must have had something to clear";
}

TEST(VoxelGrid, MemoryDoesNotGrowAndDecayedVoxelsAreFreed) {
  // A robot driving a long way through random clutter for 100 s of scans.
  core::VoxelGrid g(small_grid());
  const size_t bytes = g.memory_bytes();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  std::uniform_real_distribution<double> h(0.0, 2.5);
  size_t max_occupied = 0;
  for (int scan = 0; scan < 1000; ++scan) {
    const double x = 0.05 * scan;  // 0.5 m/s
    g.recentre(x, 0.0);
    std::vector<Ray> rays;
    rays.reserve(500);
    for (int i = 0; i < 500; ++i) {
      rays.push_back(ray_to(x + u(rng), u(rng), h(rng), Point3{x, 0.0, 0.5}));
    }
    const Nanos now = std::chrono::milliseconds(100 * scan);
    g.insert(rays, core::Pose2{x, 0, 0}, std::nullopt, now);
    g.decay(now);
    max_occupied = std::max(max_occupied, g.occupied_count());
  }
  EXPECT_EQ(g.memory_bytes(), bytes);
  // At most decay_s (2 s = 20 scans) of marks survive: bounded by 20 x 500.
  EXPECT_LE(max_occupied, 20U * 500U);
  EXPECT_GT(g.stats().decayed + g.stats().cleared + g.stats().seen_through, g.stats().marked / 2)
      << "marks are freed (by rays and by age; the rest left the window), not hidden";
}

TEST(VoxelGrid, AWalkingPersonLeavesNoTrail) {
  // An obstacle moves 1 m sideways per second in front of a wall; without the person mask
  // (it is not the tracked person). The rays through its old places clear them scan by scan:
  // within the decay time nothing but its current place and the wall is left.
  core::VoxelGrid g(small_grid());
  g.recentre(0, 0);
  for (int scan = 0; scan <= 30; ++scan) {
    const double y = -1.5 + 0.1 * scan;  // 1 m/s at 10 Hz
    std::vector<Ray> rays;
    for (int k = 0; k <= 200; ++k) {  // a ray every 2 cm, -2 to 2 m
      const double yy = -2.0 + 0.02 * k;
      const bool blocked = std::abs(yy - y) < 0.15;
      rays.push_back(ray_to(blocked ? 2.0 : 3.5, blocked ? yy * 2.0 / 3.5 : yy, 0.5));
    }
    const Nanos now = std::chrono::milliseconds(100 * scan);
    g.insert(rays, {}, std::nullopt, now);
    g.decay(now);
  }
  // The obstacle's start (y = -1.5 at 2 m, scaled) is clear again; the wall is intact.
  EXPECT_FALSE(g.occupied(2.0, -1.5 * 2.0 / 3.5, 0.5));
  EXPECT_TRUE(g.occupied(3.5, -1.5, 0.5));
  EXPECT_TRUE(g.occupied(2.0, 1.5 * 2.0 / 3.5, 0.5)) << "where it is now";
}

// A VLP-16-like revolution (16 beams, -15..15 degrees, every 0.2 degrees of azimuth within
// +-60 degrees) from `origin` into a scene of standing cylinders (1.75 m tall), a wall at
// x = wall_x_m and the ground; beams that hit nothing within 8 m return no-return rays.
struct Cylinder {
  double x, y, r;
};
std::vector<Ray> revolution(const Point3& origin, const std::vector<Cylinder>& people,
                            double wall_x_m) {
  std::vector<Ray> rays;
  constexpr double kMax = 8.0;
  for (double az_deg = -60.0; az_deg <= 60.0; az_deg += 0.2) {
    const double az = az_deg * std::numbers::pi / 180.0;
    for (int b = 0; b < 16; ++b) {
      const double el = (-15.0 + 2.0 * b) * std::numbers::pi / 180.0;
      const double dx = std::cos(az) * std::cos(el);
      const double dy = std::sin(az) * std::cos(el);
      const double dz = std::sin(el);
      double t = kMax;
      if (dz < 0) t = std::min(t, -origin.z / dz);  // the ground
      if (dx > 1e-9) {
        const double tw = (wall_x_m - origin.x) / dx;
        if (tw > 0 && origin.z + tw * dz < 2.5) t = std::min(t, tw);
      }
      for (const Cylinder& c : people) {
        // Horizontal ray-circle, then the cylinder's height.
        const double h = std::hypot(dx, dy);
        const double ux = dx / h, uy = dy / h;
        const double px = origin.x - c.x, py = origin.y - c.y;
        const double bq = px * ux + py * uy;
        const double disc = bq * bq - (px * px + py * py - c.r * c.r);
        if (disc < 0) continue;
        const double s = -bq - std::sqrt(disc);  // horizontal distance to the surface
        if (s <= 0) continue;
        const double tc = s / h;
        if (origin.z + tc * dz < 1.75) t = std::min(t, tc);
      }
      Ray r{origin, Point3{origin.x + t * dx, origin.y + t * dy, origin.z + t * dz}};
      r.hit = t < kMax;
      rays.push_back(r);
    }
  }
  return rays;
}

// A pedestrian crosses 3 m ahead of a robot that drives on at 1 m/s; a wall stands at 5 m.
// Returns whether the place the pedestrian started from is still an obstacle after 1.5 s.
bool trail_left(bool clear_seen_through, bool* wall_kept) {
  auto cfg = small_grid();
  cfg.size_xy_m = 12.0;
  cfg.resolution_m = 0.05;
  cfg.clear_max_range_m = 8.0;
  cfg.clear_seen_through = clear_seen_through;
  core::VoxelGrid g(cfg);
  for (int scan = 0; scan <= 15; ++scan) {
    const double x = 0.1 * scan;
    g.recentre(x, 0.0);
    const std::vector<Cylinder> people{{3.0, -1.0 + 0.12 * scan, 0.25}};
    const Nanos now = std::chrono::milliseconds(100 * scan);
    g.insert(revolution(Point3{x, 0.0, 0.45}, people, 5.0), core::Pose2{x, 0, 0}, std::nullopt,
             now);
    g.decay(now);
  }
  *wall_kept = false;
  for (double z = 0.1; z < 1.0; z += 0.05)
    *wall_kept = *wall_kept || g.occupied(5.01, 0.0, z) || g.occupied(4.99, 0.0, z);
  bool trail = false;
  for (double z = 0.1; z < 1.75; z += 0.05) {
    for (double y = -1.3; y <= -0.7; y += 0.05)
      trail = trail || g.occupied(2.76, y, z) || g.occupied(2.81, y, z);
  }
  return trail;
}

TEST(VoxelGrid, FromAMovingRobotWhatWasSeenThroughIsFreedAndWallsStay) {
  // The beams of a moving sensor cross a vacated place at other heights than those that marked
  // it: ray casting alone leaves a trail for decay_s.
  bool wall = false;
  EXPECT_TRUE(trail_left(false, &wall)) << "the premise: ray casting alone leaves the trail";
  EXPECT_TRUE(wall);
  EXPECT_FALSE(trail_left(true, &wall)) << "the beams beside those voxels passed beyond them";
  EXPECT_TRUE(wall) << "a wall the beams hit at other heights each scan is not seen through";
}

TEST(VoxelGrid, WhatIsHiddenBehindSomeoneFadesAfterHiddenDecayNotBefore) {
  // A post 5 m ahead, then someone steps in front of it (3 m ahead) and stays: the post is not
  // seen through; it stays for hidden_decay_s (0.5 s), then fades (in view but not seen: the
  // frustum acceleration of the spatio-temporal voxel layer), well before decay_s (2 s).
  auto cfg = small_grid();
  cfg.size_xy_m = 12.0;
  cfg.resolution_m = 0.05;
  cfg.clear_max_range_m = 8.0;
  cfg.hidden_decay_s = 0.5;
  core::VoxelGrid g(cfg);
  g.recentre(0, 0);
  const Point3 sensor{0.0, 0.0, 0.45};
  auto post = [&] {
    bool any = false;
    for (double z = 0.1; z < 1.0; z += 0.05)
      any = any || g.occupied(4.92, 0.0, z);
    return any;
  };
  g.insert(revolution(sensor, {{5.0, 0.0, 0.1}}, 50.0), {}, std::nullopt, 0ms);
  ASSERT_TRUE(post());
  for (int scan = 1; scan <= 15; ++scan) {
    const Nanos now = std::chrono::milliseconds(100 * scan);
    g.insert(revolution(sensor, {{5.0, 0.0, 0.1}, {3.0, 0.0, 0.3}}, 50.0), {}, std::nullopt, now);
    g.decay(now);
    if (scan == 4) {
      EXPECT_TRUE(post()) << "hidden for 0.4 s: kept";
    }
  }
  EXPECT_FALSE(post()) << "hidden for 1.5 s: faded";
  EXPECT_EQ(g.stats().seen_through, 0U);
  EXPECT_GT(g.stats().hidden_decayed, 0U);
  EXPECT_EQ(g.stats().decayed, 0U);
}

// ---- costmap -----------------------------------------------------------------------------------

TEST(Costmap, FollowsTheDocumentedMapping) {
  core::VoxelGrid g(small_grid());
  g.recentre(0, 0);
  g.insert(std::vector<Ray>{ray_to(2.05, 0.05, 0.5)}, {}, std::nullopt, 1s);  // cell centre
  core::CostmapConfig cc;  // r_in 0.35, inflation 1.2, k 3
  core::Costmap m;
  m.build(g, cc, 1s);
  EXPECT_EQ(m.obstacle_cells(), 1U);
  EXPECT_EQ(m.at(2.05, 0.05), 100);
  EXPECT_EQ(m.at(2.05 + 0.3, 0.05), 100) << "inside the inscribed radius: lethal";
  // 0.5 m away: 99 exp(-3 (0.5 - 0.35)) = 63.1
  EXPECT_EQ(m.at(2.55, 0.05), 63);
  // 0.8 m: 99 exp(-3 * 0.45) = 25.7 -> 26, below R = 30
  EXPECT_EQ(m.at(2.05, 0.85), 26);
  EXPECT_EQ(m.at(2.05 + 1.3, 0.05), 0) << "beyond the inflation radius";
  EXPECT_EQ(m.at(100.0, 0.0), 100) << "outside the map is not free";
  // Bilinear between two cell centres.
  const double mid = m.cost(2.60, 0.05);
  EXPECT_NEAR(mid, 0.5 * (m.at(2.55, 0.05) + m.at(2.65, 0.05)), 1e-9);
  EXPECT_EQ(m.stamp(), 1s);
}

// A 4 m grid (0.1 m cells) centred on the origin, for obstacles scattered at random.
core::VoxelGrid four_metre_grid() {
  auto cfg = small_grid();
  cfg.size_xy_m = 4.0;
  core::VoxelGrid g(cfg);
  g.recentre(0, 0);
  return g;
}

// `count` returns straight down at random places on the grid, marked at time t (the robot
// elsewhere: no self filter).
void scatter_obstacles(core::VoxelGrid& g, std::mt19937& rng, int count, Nanos t) {
  std::uniform_real_distribution<double> u(-1.95, 1.95);
  std::vector<Ray> rays;
  for (int i = 0; i < count; ++i)
    rays.push_back(ray_to(u(rng), u(rng), 0.5, Point3{0, 0, 3.0}));
  g.insert(rays, core::Pose2{10, 10, 0}, std::nullopt, t);
}

TEST(Costmap, DistanceTransformIsExact) {
  core::VoxelGrid g = four_metre_grid();
  std::mt19937 rng(3);
  scatter_obstacles(g, rng, 25, 1s);
  core::CostmapConfig cc;
  cc.inscribed_radius_m = 0.0;
  cc.inflation_radius_m = 10.0;
  cc.cost_scaling_per_m = 1.0;
  core::Costmap m;
  m.build(g, cc, 1s);
  const int n = m.cells();
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      double best = 1e9;
      for (int b = 0; b < n; ++b) {
        for (int a = 0; a < n; ++a) {
          if (g.column(a, b) != 0) best = std::min(best, std::hypot(a - i, b - j) * 0.1);
        }
      }
      const int expected =
          best == 0.0 ? 100 : static_cast<int>(std::lround(99.0 * std::exp(-best)));
      ASSERT_EQ(m.cell(i, j), expected) << i << "," << j;
    }
  }
}

// The obstacle layer (what the controller's obstacle speed limit reads): exactly the columns
// with an occupied voxel, not the lethal ring the inflation puts round them; rebuilt with the
// cells, carried by a snapshot's copy, false off the map.
TEST(Costmap, ObstacleCellsAreTheOccupiedColumnsAndTravelWithACopy) {
  core::VoxelGrid g = four_metre_grid();
  std::mt19937 rng(5);
  core::Costmap m;
  auto check = [&](const core::Costmap& map, const char* what) {
    size_t obstacles = 0;
    size_t lethal_not_obstacle = 0;
    for (int j = 0; j < map.cells(); ++j) {
      for (int i = 0; i < map.cells(); ++i) {
        ASSERT_EQ(map.obstacle(i, j), g.column(i, j) != 0) << what << " " << i << "," << j;
        obstacles += map.obstacle(i, j) ? 1U : 0U;
        lethal_not_obstacle += !map.obstacle(i, j) && map.cell(i, j) == core::kCostLethal;
      }
    }
    EXPECT_EQ(obstacles, map.obstacle_cells()) << what;
    EXPECT_GT(lethal_not_obstacle, 0U) << what << ": the inscribed ring is lethal, not obstacle";
    EXPECT_FALSE(map.obstacle(-1, 0));
    EXPECT_FALSE(map.obstacle(0, map.cells()));
  };
  scatter_obstacles(g, rng, 25, 1s);
  m.build(g, core::CostmapConfig{}, 1s);
  check(m, "built");
  scatter_obstacles(g, rng, 25, 2s);
  m.build(g, core::CostmapConfig{}, 2s);
  check(m, "rebuilt");
  core::Costmap copy;
  copy.copy_cells_from(m);
  check(copy, "copied");
}

// Each obstacle cell carries how long its column has been occupied (the grid's age, in steps of
// kObstacleAgeStepS, older than kObstacleAgeMaxS read as that), taken when the map is built,
// and carries it in a snapshot's copy.
TEST(Costmap, ObstacleCellsCarryTheirColumnsAge) {
  core::VoxelGrid g = four_metre_grid();
  std::mt19937 rng(9);
  scatter_obstacles(g, rng, 25, 1s);
  scatter_obstacles(g, rng, 25, 1730ms);
  core::Costmap m;
  auto check = [&](const core::Costmap& map, Nanos built, double first_age_s) {
    size_t first = 0;
    for (int j = 0; j < map.cells(); ++j) {
      for (int i = 0; i < map.cells(); ++i) {
        const double grid_age = g.occupied_for_s(i, j, built);
        const double expected =
            std::min(std::floor(grid_age / core::Costmap::kObstacleAgeStepS + 1e-6),
                     core::Costmap::kObstacleAgeMaxS / core::Costmap::kObstacleAgeStepS) *
            core::Costmap::kObstacleAgeStepS;
        ASSERT_NEAR(map.obstacle_age_s(i, j), expected, 1e-9) << i << "," << j;
        first += std::abs(map.obstacle_age_s(i, j) - first_age_s) < 1e-9 ? 1U : 0U;
      }
    }
    EXPECT_GT(first, 10U) << "the first scan's cells";
  };
  m.build(g, core::CostmapConfig{}, 2s);
  check(m, 2s, 1.0);  // the second scan's: 0.27 s, read as 0.25
  m.build(g, core::CostmapConfig{}, 60s);
  check(m, 60s, core::Costmap::kObstacleAgeMaxS);
  core::Costmap copy;
  copy.copy_cells_from(m);
  check(copy, 60s, core::Costmap::kObstacleAgeMaxS);
  EXPECT_EQ(m.obstacle_age_s(-1, 0), 0.0);
}

// The controller's collision test (cost_at_least: a quad's cell range decides most points
// without interpolating) gives exactly the answer of cost(x, y) >= threshold: everywhere on and
// off the map, on cell centres and quad edges, at the thresholds where rounding could tell them
// apart (a corner exactly at the threshold), for a map built again (ranges refreshed) and for a
// snapshot's copy. A range that ignored the off-map corners, missed a rebuild or was not copied
// with the cells would disagree here.
TEST(Costmap, CollisionTestEqualsTheInterpolatedCostAgainstTheThreshold) {
  core::VoxelGrid g = four_metre_grid();
  std::mt19937 rng(11);
  const core::CostmapConfig cc;
  core::Costmap m;
  core::Costmap empty;  // never built: no cells, everything off the map
  std::uniform_real_distribution<double> anywhere(-2.6, 2.6);  // the map is +-2 m
  std::uniform_int_distribution<int> cell_index(-3, 42);
  std::uniform_int_distribution<int> quarter(0, 4);
  const double thresholds[] = {30.0, 29.5, 30.5, 0.0, 1.0, 63.0, 99.0, 100.0, 100.5, -1.0};
  size_t fast_true = 0, fast_false = 0;
  auto check = [&](const core::Costmap& map, const char* what) {
    for (int n = 0; n < 60000; ++n) {
      double x = anywhere(rng), y = anywhere(rng);
      if (n % 3 == 0) {  // on cell centres, edges and quarter points, where corners weigh 0 or 1
        x = map.origin_x() + (cell_index(rng) + 0.25 * quarter(rng)) * map.resolution();
        y = map.origin_y() + (cell_index(rng) + 0.25 * quarter(rng)) * map.resolution();
      }
      const double c = map.cost(x, y);
      // Thresholds at the corner values themselves too (a quad with a corner exactly at it).
      const double at_cell = map.at(x, y);
      for (const double t : {thresholds[n % 10], at_cell, c}) {
        const bool want = c >= t;
        ASSERT_EQ(map.cost_at_least(x, y, t), want)
            << what << " at " << x << "," << y << " t=" << t;
        (want ? fast_true : fast_false) += 1;
      }
    }
  };
  scatter_obstacles(g, rng, 25, 1s);
  m.build(g, cc, 1s);
  check(m, "built");
  scatter_obstacles(g, rng, 25, 2s);  // more obstacles: the ranges must follow the new cells
  m.build(g, cc, 2s);
  check(m, "rebuilt");
  core::Costmap copy;
  copy.copy_cells_from(m);
  check(copy, "copied");
  for (const double t : thresholds) {
    EXPECT_EQ(empty.cost_at_least(0.0, 0.0, t), 100.0 >= t);
    EXPECT_EQ(m.cost_at_least(std::nan(""), 0.0, t), m.cost(std::nan(""), 0.0) >= t);
    EXPECT_EQ(m.cost_at_least(1e12, 0.0, t), m.cost(1e12, 0.0) >= t);
  }
  EXPECT_GT(fast_true, 10000U);  // both answers were exercised
  EXPECT_GT(fast_false, 10000U);
}

}  // namespace

#include "core/perception/deskew.hpp"

namespace {

TEST(Deskew, EachReturnUsesThePoseAtItsTime) {
  // The robot drives at 1 m/s along x and turns 90 deg/s; a wall point seen at 0 and at 100 ms
  // from different robot poses lands at the same odom position after deskewing.
  core::PoseHistory h(64, 20ms);
  for (int i = 0; i <= 10; ++i) {
    const double t = 0.02 * i;
    h.add({1.0 * t, 0.0, M_PI / 2 * t}, std::chrono::milliseconds(20 * i));
  }
  const core::Point3 wall{3.0, 1.0, 0.5};  // odom
  std::vector<core::TimedPoint> in;
  for (Nanos t : {0ms, 50ms, 100ms, 150ms}) {
    const core::Pose2 robot = *h.at(t);
    const core::Point2 b = robot.inverse().apply({wall.x, wall.y});
    in.push_back({b.x_m, b.y_m, wall.z, t});
  }
  in.push_back({1.0, 0.0, 0.5, 500ms});  // no odometry that late: dropped
  std::vector<core::Ray> out(in.size());
  const auto r = core::deskew(in, h, core::Point3{0.1, 0.0, 0.45}, out, 1ns);
  ASSERT_EQ(r.rays, 4U);
  EXPECT_EQ(r.no_pose, 1U);
  for (size_t i = 0; i < r.rays; ++i) {
    EXPECT_NEAR(out[i].end.x, wall.x, 1e-9) << i;
    EXPECT_NEAR(out[i].end.y, wall.y, 1e-9) << i;
  }
  // The ray starts at the sensor, 0.1 m ahead of the robot at that time (at 100 ms: x = 0.1,
  // heading 9 deg).
  EXPECT_NEAR(out[2].origin.x, 0.1 + 0.1 * std::cos(M_PI / 20), 1e-9);
  EXPECT_NEAR(out[2].origin.y, 0.1 * std::sin(M_PI / 20), 1e-9);
}

}  // namespace

TEST(Costmap, DistanceAtCostInvertsTheScale) {
  const core::CostmapConfig c;
  // The header's statement: R = 30 is reached at ~0.75 m.
  EXPECT_NEAR(core::distance_at_cost(c, 30.0), 0.748, 0.001);
  for (double cost : {10.0, 30.0, 60.0, 98.0}) {
    const double d = core::distance_at_cost(c, cost);
    EXPECT_NEAR(core::cost_at_distance(c, d), cost, 1e-9) << cost;
  }
  // Costs below the one at the inflation radius (~7.7): the radius.
  EXPECT_DOUBLE_EQ(core::distance_at_cost(c, 1.0), c.inflation_radius_m);
}
