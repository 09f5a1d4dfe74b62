// Observation layout 1: every section at its documented offset, with the documented values.
#include <gtest/gtest.h>

#include <numbers>

#include "core/perception/voxel_grid.hpp"
#include "core/policy/observation.hpp"

using namespace std::chrono_literals;

namespace {

TEST(Observation, SizeIsSevenNPlus268) {
  EXPECT_EQ(core::observation_size(64), 716U);
  EXPECT_EQ(core::observation_size(4), 296U);
}

TEST(Observation, LayoutOneRoundTrip) {
  // A wall 1 m to the robot's left (odom = base_link), the person 1.5 m ahead.
  core::VoxelGridConfig gc;
  gc.size_xy_m = 8.0;
  core::VoxelGrid g(gc);
  g.recentre(0, 0);
  std::vector<core::Ray> rays;
  for (double x = -3.9; x <= 3.9; x += 0.02)
    rays.push_back({{0, -2, 3.0}, {x, 1.0, 0.5}});
  g.insert(rays, core::Pose2{20, 20, 0}, std::nullopt, 1s);
  core::Costmap map;
  map.build(g, core::CostmapConfig{}, 1s);

  core::InteractiveSpaceConfig sc;
  sc.points = 8;
  core::InteractiveSpace space(sc);
  const core::Pose2 person{1.5, 0.0, 0.0};
  space.update(person, core::Pose2{}, map);

  core::ObservationInputs in;
  in.space = &space;
  in.costmap = &map;
  in.robot_vx_mps = 0.4;
  in.robot_vy_mps = -0.1;
  in.robot_wz_radps = 0.2;
  in.human.valid = true;
  in.human.pose_base = person;
  in.human.velocity_base = {1.1, 0.05};
  in.human.yaw_rate_radps = -0.3;
  in.previous_action = 4;
  const size_t n = 8;
  std::vector<float> obs(core::observation_size(n), -99.0f);
  ASSERT_TRUE(core::build_observation(in, obs));

  const auto cs = space.candidates();
  for (size_t i = 0; i < n; ++i) {
    const bool p = cs[i].free;
    EXPECT_FLOAT_EQ(obs[4 * i + 0], p ? static_cast<float>(cs[i].dist_human_m) : 0.0f);
    EXPECT_FLOAT_EQ(obs[4 * i + 1], p ? static_cast<float>(cs[i].dist_robot_m) : 0.0f);
    EXPECT_FLOAT_EQ(obs[4 * i + 2], p ? static_cast<float>(cs[i].cost) : 0.0f);
    EXPECT_FLOAT_EQ(obs[4 * i + 3], p ? static_cast<float>(cs[i].objective) : 0.0f);
    EXPECT_FLOAT_EQ(obs[4 * n + 3 * i + 0], p ? static_cast<float>(cs[i].base.x_m) : 0.0f);
    EXPECT_FLOAT_EQ(obs[4 * n + 3 * i + 1], p ? static_cast<float>(cs[i].base.y_m) : 0.0f);
    EXPECT_FLOAT_EQ(obs[4 * n + 3 * i + 2], p ? 1.0f : 0.0f);
  }
  // Point 2 (phi = 90 deg) is on the person's left, (1.5, 0.7): 0.3 m from the wall -> not in P.
  EXPECT_FLOAT_EQ(obs[4 * n + 3 * 2 + 2], 0.0f);
  EXPECT_FLOAT_EQ(obs[4 * 2 + 0], 0.0f);
  // Patch: row r covers y = -1.875 + 0.25 (r + 0.5) ... the row at y = 0.875..1.125 (r = 11) holds
  // the wall: lethal (1.0); row 0 (y = -1.875 m, 2.9 m from the wall) is free; the row through
  // the robot (y = -0.125 m, 1.1 m from the wall) is inflated: 99 exp(-3 (1.125 - 0.35)) = 10.
  const size_t patch = 7 * n;
  EXPECT_FLOAT_EQ(obs[patch + 11 * 16 + 8], 1.0f);
  EXPECT_FLOAT_EQ(obs[patch + 0 * 16 + 8], 0.0f);
  EXPECT_NEAR(obs[patch + 7 * 16 + 8], 0.10f, 0.011f);
  const size_t tail = patch + 256;
  EXPECT_FLOAT_EQ(obs[tail + 0], 0.4f);
  EXPECT_FLOAT_EQ(obs[tail + 1], -0.1f);
  EXPECT_FLOAT_EQ(obs[tail + 2], 0.2f);
  EXPECT_FLOAT_EQ(obs[tail + 3], 1.5f);
  EXPECT_FLOAT_EQ(obs[tail + 4], 0.0f);
  EXPECT_FLOAT_EQ(obs[tail + 5], 0.0f);
  EXPECT_FLOAT_EQ(obs[tail + 6], 1.1f);
  EXPECT_FLOAT_EQ(obs[tail + 7], 0.05f);
  EXPECT_FLOAT_EQ(obs[tail + 8], -0.3f);
  EXPECT_FLOAT_EQ(obs[tail + 9], static_cast<float>(cs[4].base.x_m));  // previous action
  EXPECT_FLOAT_EQ(obs[tail + 10], static_cast<float>(cs[4].base.y_m));
  EXPECT_FLOAT_EQ(obs[tail + 11], 1.0f);
  EXPECT_EQ(tail + 12, obs.size());
  EXPECT_EQ(std::count(obs.begin(), obs.end(), -99.0f), 0) << "every slot written";

  // A wrong size writes nothing.
  std::vector<float> small(10, 5.0f);
  EXPECT_FALSE(core::build_observation(in, small));
  EXPECT_EQ(small[0], 5.0f);
}

}  // namespace
