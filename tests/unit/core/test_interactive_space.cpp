// The interactive space W, the collision-free set P and the objective selector (paper, sec. III).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>

#include "core/perception/costmap.hpp"
#include "core/perception/voxel_grid.hpp"
#include "core/planner/goal_hold.hpp"
#include "core/planner/goal_slew.hpp"
#include "core/planner/interactive_space.hpp"

using std::numbers::pi;
using namespace std::chrono_literals;

namespace {

// A costmap of an empty 8 m room with walls along y = each of `wall_ys` (odom), 0.5 m high.
core::Costmap walled_room(std::initializer_list<double> wall_ys) {
  core::VoxelGridConfig gc;
  gc.size_xy_m = 8.0;
  gc.resolution_m = 0.05;
  core::VoxelGrid g(gc);
  g.recentre(0, 0);
  std::vector<core::Ray> rays;
  for (const double y : wall_ys) {
    for (int k = 0; k <= 390; ++k)  // x from -3.9 to 3.9 m every 2 cm
      rays.push_back({{0.0, 0.0, 3.0}, {-3.9 + 0.02 * k, y, 0.5}});
  }
  g.insert(rays, core::Pose2{20, 20, 0}, std::nullopt, 1s);
  core::Costmap m;
  m.build(g, core::CostmapConfig{}, 1s);
  return m;
}

// An empty 8 m room, or one with a wall along y = wall_y.
core::Costmap room(std::optional<double> wall_y) {
  return wall_y ? walled_room({*wall_y}) : walled_room({});
}

TEST(InteractiveSpace, PointsLieOnTheEllipseAroundThePersonInBaseLink) {
  core::InteractiveSpaceConfig cfg;
  cfg.points = 4;
  core::InteractiveSpace w(cfg);
  // The person 2 m ahead, facing left (+y).
  w.update(core::Pose2{2.0, 0.0, pi / 2}, core::Pose2{}, room(std::nullopt));
  const auto c = w.candidates();
  ASSERT_EQ(c.size(), 4U);
  // phi = 0: a = 1 m along the person's heading -> (2, 1); phi = 90 deg: b = 0.7 m to the
  // person's left -> (1.3, 0); phi = 180 deg: behind -> (2, -1).
  EXPECT_NEAR(c[0].base.x_m, 2.0, 1e-12);
  EXPECT_NEAR(c[0].base.y_m, 1.0, 1e-12);
  EXPECT_NEAR(c[1].base.x_m, 1.3, 1e-12);
  EXPECT_NEAR(c[1].base.y_m, 0.0, 1e-12);
  EXPECT_NEAR(c[2].base.y_m, -1.0, 1e-12);
  // The same points in the person's frame, whatever the person's pose.
  EXPECT_NEAR(w.point_in_person(0).x_m, 1.0, 1e-12);
  EXPECT_NEAR(w.point_in_person(1).y_m, 0.7, 1e-12);
  EXPECT_NEAR(w.point_in_person(2).x_m, -1.0, 1e-12);
  for (const auto& p : c) {
    EXPECT_NEAR(p.base.theta_rad, pi / 2, 1e-12) << "desired heading = the person's";
    EXPECT_TRUE(p.free);
  }
  EXPECT_NEAR(c[1].dist_robot_m, 1.3, 1e-12);
  EXPECT_NEAR(c[1].dist_human_m, 0.7, 1e-12);
  // G = alpha |P - q_h| + beta |P| + gamma l
  EXPECT_NEAR(c[1].objective, cfg.alpha * 0.7 + cfg.beta * 1.3 + cfg.gamma * 0.0, 1e-12);
  // With the robot elsewhere in odom, the costmap is looked up at the odom position.
  w.update(core::Pose2{2.0, 0.0, pi / 2}, core::Pose2{1.0, 1.0, pi}, room(std::nullopt));
  EXPECT_NEAR(w.candidates()[1].odom.x_m, 1.0 - 1.3, 1e-12);
  EXPECT_NEAR(w.candidates()[1].odom.y_m, 1.0, 1e-12);
}

TEST(InteractiveSpace, PExcludesPointsInObstaclesAndArgminPicksTheOpenSide) {
  // The person walks along +x, 1 m ahead of the robot, with a wall 0.9 m to their left.
  core::InteractiveSpace w(core::InteractiveSpaceConfig{});
  const core::Pose2 person{1.0, 0.0, 0.0};
  w.update(person, core::Pose2{}, room(0.9));
  EXPECT_LT(w.free_count(), 64U);
  for (const auto& c : w.candidates()) {
    if (c.base.y_m > 0.5) {
      EXPECT_FALSE(c.free) << "within 0.4 m of the wall: cost >= R";
      EXPECT_GE(c.cost, 30.0);
    }
  }
  const auto s = core::select_by_objective(w);
  ASSERT_EQ(s.status, core::GoalStatus::kOk);
  EXPECT_LT(s.goal_base.y_m, 0.1) << "beside/behind, on the open side, not by the wall";
  // Without the wall the same situation may use either side; the choice is deterministic.
  core::InteractiveSpace open(core::InteractiveSpaceConfig{});
  open.update(person, core::Pose2{}, room(std::nullopt));
  const auto s1 = core::select_by_objective(open);
  const auto s2 = core::select_by_objective(open);
  EXPECT_EQ(s1.index, s2.index);
  EXPECT_EQ(open.free_count(), 64U);
}

TEST(InteractiveSpace, DefaultWeightsSendALaggingRobotBehindThePersonNotBesideThem) {
  // The robot lags 2.5 m behind a person walking along +x, 0.9 m to their right. The weights
  // (beta = 4, alpha = -16, chosen on validation seeds: docs/EVALUATION.md) make G prefer the
  // ellipse point nearest the robot, and the far points, over the person's near side: the
  // robot closes in behind, where the closing-speed limit can brake for a person who turns,
  // instead of cutting across to their side (beta = 0.5 chose 0.49 m to the side here).
  const core::InteractiveSpaceConfig cfg;
  core::InteractiveSpace w(cfg);
  const core::Pose2 person{2.5, 0.9, 0.0};
  w.update(person, core::Pose2{}, room(std::nullopt));
  const auto s = core::select_by_objective(w);
  ASSERT_EQ(s.status, core::GoalStatus::kOk);
  const double behind_m = person.x_m - s.goal_base.x_m;
  const double aside_m = person.y_m - s.goal_base.y_m;
  EXPECT_GT(behind_m, 0.9) << "behind the person, near the ellipse's a = 1 m";
  EXPECT_LT(std::abs(aside_m), 0.3) << "near straight behind, not beside";
  EXPECT_GT(aside_m, 0.0) << "on the robot's side of the person's track";
}

TEST(InteractiveSpace, SwitchCostKeepsThePointChosenLastOnANearTieButNotOnAClearPreference) {
  // The robot at the right-hand point of a person walking along +x (the person 0.7 m to its
  // left): with the default weights G prefers a point behind-right by 0.14 (the far points,
  // alpha < 0), 13 steps round the ellipse; the last choice was the right-hand point (48 of 64).
  core::InteractiveSpaceConfig cfg;
  ASSERT_DOUBLE_EQ(cfg.switch_cost, 0.0) << "the paper's G by default";
  const int right = 48;
  const auto select = [&](double switch_cost, const core::Pose2& person, int previous) {
    core::InteractiveSpaceConfig c = cfg;
    c.switch_cost = switch_cost;
    core::InteractiveSpace w(c);
    w.update(person, core::Pose2{}, room(std::nullopt));
    return core::select_by_objective(w, previous);
  };
  const core::Pose2 beside{0.0, 0.7, 0.0};
  const core::Selection paper = select(0.0, beside, right);
  ASSERT_EQ(paper.status, core::GoalStatus::kOk);
  EXPECT_EQ(paper.index, 35) << "behind-right: G's own choice, the previous point ignored";
  EXPECT_EQ(select(0.05, beside, right).index, right) << "0.05 a step: 0.65 for 13 steps";
  EXPECT_EQ(select(0.05, beside, -1).index, 35) << "nothing chosen before: G alone";
  // The robot 0.3 m behind that (G's preference 2.4): q^d still moves, most of the way.
  const core::Selection lagging = select(0.05, core::Pose2{0.3, 0.7, 0.0}, right);
  EXPECT_GE(lagging.index, 35);
  EXPECT_LE(lagging.index, 38);
  // A previous point that is no longer free is not kept: a wall 0.4 m right of the person.
  core::InteractiveSpaceConfig c = cfg;
  c.switch_cost = 0.05;
  core::InteractiveSpace walled(c);
  walled.update(core::Pose2{0.0, -0.4, 0.0}, core::Pose2{}, room(-1.0));
  ASSERT_FALSE(walled.candidates()[right].free);
  const core::Selection moved = core::select_by_objective(walled, right);
  ASSERT_EQ(moved.status, core::GoalStatus::kOk);
  EXPECT_NE(moved.index, right);
  EXPECT_TRUE(walled.candidates()[static_cast<size_t>(moved.index)].free);
}

TEST(InteractiveSpace, DeltaDropsAPushedAsideLeaderBehindButKeepsOneThatIsAhead) {
  // The person at the origin walks along +x. The default delta = 4 per metre ahead; the paper's G
  // has none.
  const core::InteractiveSpaceConfig cfg;
  ASSERT_DOUBLE_EQ(cfg.delta, 4.0);
  core::InteractiveSpaceConfig paper;
  paper.delta = 0.0;
  const auto chosen_x_in_person = [&](const core::InteractiveSpaceConfig& c,
                                      const core::Pose2& robot_odom) {
    core::InteractiveSpace w(c);
    // The person seen from the robot: base_link = the robot's frame.
    const core::Pose2 person_base = robot_odom.inverse() * core::Pose2{0.0, 0.0, 0.0};
    w.update(person_base, robot_odom, room(std::nullopt));
    const auto s = core::select_by_objective(w);
    EXPECT_EQ(s.status, core::GoalStatus::kOk);
    return robot_odom.apply({s.goal_base.x_m, s.goal_base.y_m}).x_m;
  };
  // A robot right at the point ahead (leading out of a dead end) keeps it: behind is 2 m
  // farther, beta 2 m = 8 > delta a = 4.
  EXPECT_GT(chosen_x_in_person(cfg, core::Pose2{1.0, 0.0, 0.0}), 0.9);
  // Pushed 1.1 m to the side and level with the person's front (the outside of a turn), the
  // point behind is only 0.6 m farther: it is chosen (the paper's G, delta 0, keeps the front).
  const core::Pose2 pushed{0.45, -1.1, 0.0};
  EXPECT_LT(chosen_x_in_person(cfg, pushed), -0.5);
  EXPECT_GT(chosen_x_in_person(paper, pushed), 0.5);
  // Points behind and beside the person are not charged: G differs by delta max(0, x) only.
  core::InteractiveSpace with(cfg);
  core::InteractiveSpace without(paper);
  with.update(core::Pose2{2.0, 0.0, 0.0}, core::Pose2{}, room(std::nullopt));
  without.update(core::Pose2{2.0, 0.0, 0.0}, core::Pose2{}, room(std::nullopt));
  for (size_t i = 0; i < with.candidates().size(); ++i) {
    const double x_in_person = with.candidates()[i].base.x_m - 2.0;
    EXPECT_NEAR(with.candidates()[i].objective - without.candidates()[i].objective,
                4.0 * std::max(0.0, x_in_person), 1e-9);
  }
}

// A ring of obstacles 0.9 m around (cx, 0) (a crowd): every ellipse point there is too close.
core::Costmap ring_around(double cx) {
  core::VoxelGridConfig gc;
  gc.size_xy_m = 8.0;
  core::VoxelGrid g(gc);
  g.recentre(0, 0);
  std::vector<core::Ray> rays;
  for (double a = 0; a < 2 * pi; a += 0.01) {
    rays.push_back({{cx, 0.0, 3.0}, {cx + 0.9 * std::cos(a), 0.9 * std::sin(a), 0.5}});
  }
  g.insert(rays, core::Pose2{-20, -20, 0}, std::nullopt, 1s);
  core::Costmap m;
  m.build(g, core::CostmapConfig{}, 1s);
  return m;
}

TEST(InteractiveSpace, ASurroundedPersonGivesNoGoalWithAReason) {
  core::InteractiveSpace w(core::InteractiveSpaceConfig{});
  w.update(core::Pose2{2.0, 0.0, 0.0}, core::Pose2{}, ring_around(2.0));
  EXPECT_EQ(w.free_count(), 0U);
  const auto s = core::select_by_objective(w);
  EXPECT_EQ(s.status, core::GoalStatus::kNoFreePoint);
  EXPECT_EQ(s.index, -1);
  EXPECT_EQ(core::to_string(s.status), "no free point around the person");
}

TEST(GoalHold, KeepsTheLastPointThroughAMomentWithoutAFreeOneThenLetsGo) {
  core::InteractiveSpace w(core::InteractiveSpaceConfig{});
  core::GoalHold hold(1500ms);
  // Open: the objective chooses a point, and it passes through.
  w.update(core::Pose2{2.0, 0.0, 0.0}, core::Pose2{}, room(std::nullopt));
  const core::Selection free = core::select_by_objective(w);
  ASSERT_EQ(free.status, core::GoalStatus::kOk);
  core::Selection s = hold.update(free, w, 10s);
  EXPECT_EQ(s.index, free.index);
  EXPECT_FALSE(hold.held());
  // The person, now 0.5 m further on, is closed in (a pedestrian passing): the same point of W,
  // moved with them, for 1.5 s.
  w.update(core::Pose2{2.5, 0.0, 0.0}, core::Pose2{}, ring_around(2.5));
  const core::Selection none = core::select_by_objective(w);
  ASSERT_EQ(none.status, core::GoalStatus::kNoFreePoint);
  s = hold.update(none, w, 11s);
  EXPECT_TRUE(hold.held());
  EXPECT_EQ(s.status, core::GoalStatus::kOk);
  EXPECT_EQ(s.index, free.index);
  EXPECT_NEAR(s.goal_base.x_m, free.goal_base.x_m + 0.5, 1e-9) << "it moves with the person";
  EXPECT_NEAR(s.goal_base.y_m, free.goal_base.y_m, 1e-9);
  s = hold.update(none, w, 11500ms);
  EXPECT_TRUE(hold.held());
  // Past the hold: no goal (the robot stops), and no memory of the old point afterwards.
  s = hold.update(none, w, 11501ms);
  EXPECT_FALSE(hold.held());
  EXPECT_EQ(s.status, core::GoalStatus::kNoFreePoint);
  EXPECT_EQ(hold.index(), -1);
  s = hold.update(none, w, 11502ms);
  EXPECT_FALSE(hold.held());
}

TEST(GoalHold, NeverHoldsWithoutAPersonOrWithAZeroHold) {
  core::InteractiveSpace w(core::InteractiveSpaceConfig{});
  w.update(core::Pose2{2.0, 0.0, 0.0}, core::Pose2{}, room(std::nullopt));
  const core::Selection free = core::select_by_objective(w);
  core::GoalHold hold(1500ms);
  hold.update(free, w, 1s);
  core::Selection lost;  // kNoPerson: the track is gone, nothing to move the point with
  EXPECT_EQ(hold.update(lost, w, 1100ms).status, core::GoalStatus::kNoPerson);
  EXPECT_FALSE(hold.held());
  core::GoalHold none(0ms);
  none.update(free, w, 1s);
  w.update(core::Pose2{2.0, 0.0, 0.0}, core::Pose2{}, ring_around(2.0));
  EXPECT_EQ(none.update(core::select_by_objective(w), w, 1010ms).status,
            core::GoalStatus::kNoFreePoint);
}

TEST(InteractiveSpace, ANegativeAlphaPullsADiagonalFollowerTowardStraightBehind) {
  // The robot follows 1.2 m behind and 0.6 m to the right of a person walking along +x. With
  // alpha > 0, G trades the short distance to the person beside them against the robot's
  // distance: q^d lands diagonally behind-right. alpha < 0 rewards the ellipse's far points
  // (a = 1 m behind against b = 0.7 m beside): q^d moves toward the person's wake.
  const core::Pose2 person{1.2, 0.6, 0.0};
  auto aside_m = [&](double alpha) {
    core::InteractiveSpaceConfig cfg;
    cfg.alpha = alpha;
    core::InteractiveSpace w(cfg);
    w.update(person, core::Pose2{}, room(std::nullopt));
    const auto s = core::select_by_objective(w);
    EXPECT_EQ(s.status, core::GoalStatus::kOk);
    EXPECT_LT(s.goal_base.x_m, person.x_m - 0.8) << "behind the person either way";
    return person.y_m - s.goal_base.y_m;
  };
  EXPECT_GT(aside_m(1.0), 0.3) << "alpha = 1: diagonally behind-right";
  EXPECT_LT(aside_m(-16.0), 0.25) << "alpha = -16: nearer straight behind";
  EXPECT_GT(aside_m(-16.0), 0.0) << "still on the robot's side of the track";
}

TEST(InteractiveSpace, SpeedStandoffMovesOutOnlyThePointsTheRobotCannotHoldAtThePersonsPace) {
  // The person 2 m ahead and 0.5 m left of the robot, facing and walking left (+y in base_link)
  // at 1 m/s; the robot's odom pose turned, so base_link, odom and the person's frame all differ.
  const core::Pose2 person{2.0, 0.5, pi / 2};
  const core::Point2 walking_base{0.0, 1.0};
  const core::Pose2 robot_odom{1.0, -0.5, 0.3};
  core::InteractiveSpaceConfig cfg;  // 64 points: 32 straight behind, 16 on the left, 0 ahead
  cfg.closing.robot_decel_mps2 = 1.0;
  const double standoff = core::follow_standoff_m({1.0, 0.0}, {1.0, 0.0}, cfg.closing);
  ASSERT_NEAR(standoff, 1.083, 0.001);
  auto run = [&](bool on, const core::Point2& velocity) {
    core::InteractiveSpaceConfig c = cfg;
    c.speed_standoff = on;
    auto w = std::make_unique<core::InteractiveSpace>(c);
    w->update(person, robot_odom, room(std::nullopt), velocity);
    return w;
  };
  const auto paper = run(false, walking_base);
  const auto on = run(true, walking_base);
  const auto standing = run(true, {0.0, 0.0});
  // The candidate's distance from the person (G keeps the design point's: dist_human_m).
  auto from_person = [&](const core::InteractiveSpace& w, size_t i) {
    const core::Pose2& b = w.candidates()[i].base;
    return std::hypot(b.x_m - person.x_m, b.y_m - person.y_m);
  };
  const auto behind = on->candidates()[32];
  EXPECT_NEAR(from_person(*on, 32), standoff, 1e-9);
  EXPECT_NEAR(from_person(*paper, 32), cfg.a_m, 1e-9);
  // Along the ray straight behind: in base_link that is -y from the person; odom moved with it.
  EXPECT_NEAR(behind.base.x_m, person.x_m, 1e-9);
  EXPECT_NEAR(behind.base.y_m, person.y_m - standoff, 1e-9);
  const core::Point2 behind_odom = robot_odom.apply({behind.base.x_m, behind.base.y_m});
  EXPECT_NEAR(behind.odom.x_m, behind_odom.x_m, 1e-9);
  EXPECT_NEAR(behind.odom.y_m, behind_odom.y_m, 1e-9);
  // G is the paper's: the same for every point with the standoff as without (an empty room).
  for (size_t i = 0; i < 64; ++i) {
    EXPECT_DOUBLE_EQ(on->candidates()[i].objective, paper->candidates()[i].objective) << i;
  }
  // Diagonally behind: moved out (farther than straight behind: the footprint's corner is
  // nearer the person); beside, ahead, and every point of a standing person: not.
  EXPECT_GT(from_person(*on, 24), from_person(*paper, 24) + 0.1);
  for (const size_t i : {0U, 8U, 16U, 48U, 56U}) {
    EXPECT_NEAR(from_person(*on, i), from_person(*paper, i), 1e-12) << i;
  }
  for (size_t i = 0; i < 64; ++i) {
    EXPECT_NEAR(from_person(*standing, i), from_person(*paper, i), 1e-12) << i;
  }
}

TEST(InteractiveSpace, SpeedStandoffStopsAtItsCap) {
  // A person walking forward at 1.7 m/s: uncapped, the point straight behind moves out to the
  // stopping gap (~1.8 m, beyond a = 1 m); a cap of 1.4 m holds it there; a cap below a moves
  // nothing (the standoff only ever moves a point out).
  const core::Pose2 person{2.0, 0.0, 0.0};
  const core::Point2 walking_base{1.7, 0.0};
  core::InteractiveSpaceConfig cfg;
  cfg.closing.robot_decel_mps2 = 1.0;
  cfg.speed_standoff = true;
  auto behind_m = [&](double cap_m) {
    core::InteractiveSpaceConfig c = cfg;
    c.speed_standoff_max_m = cap_m;
    core::InteractiveSpace w(c);
    w.update(person, core::Pose2{}, room(std::nullopt), walking_base);
    const core::Pose2& b = w.candidates()[32].base;
    return std::hypot(b.x_m - person.x_m, b.y_m - person.y_m);
  };
  const double uncapped = behind_m(0.0);
  EXPECT_GT(uncapped, 1.6);
  EXPECT_NEAR(behind_m(1.4), 1.4, 1e-9);
  EXPECT_NEAR(behind_m(0.5), cfg.a_m, 1e-9);
  EXPECT_NEAR(behind_m(5.0), uncapped, 1e-12);
}

}  // namespace

core::Selection choice_of(const core::InteractiveSpace& w, int index) {
  return core::Selection{core::GoalStatus::kOk, index,
                         w.candidates()[static_cast<size_t>(index)].base};
}

// The person 2 m ahead of the robot, walking along +x: 64 points, 0 ahead of them, 16 on their
// left, 32 behind, 48 on their right.
core::Pose2 person_ahead() {
  return core::Pose2{2.0, 0.0, 0.0};
}

TEST(GoalSlew, StepsRoundTheEllipseAtTheRateThenHoldsTheArgmin) {
  core::InteractiveSpace w(core::InteractiveSpaceConfig{});
  w.update(person_ahead(), core::Pose2{}, walled_room({}));
  // From the left-hand point to the right-hand one, 32 steps either way: at 30 points a second
  // and one update per 1/30 s, one step an update; each point on the way is q^d in turn.
  core::GoalSlew slew(30.0);
  int from = 16;
  for (int k = 1; k <= 32; ++k) {
    const core::Selection s = slew.update(choice_of(w, 48), from, w, 33'333'334ns);
    ASSERT_EQ(s.status, core::GoalStatus::kOk);
    ASSERT_EQ(s.index, 16 + k) << "update " << k;
    EXPECT_EQ(s.goal_base.x_m, w.candidates()[static_cast<size_t>(s.index)].base.x_m);
    EXPECT_EQ(s.goal_base.y_m, w.candidates()[static_cast<size_t>(s.index)].base.y_m);
    from = s.index;
  }
  EXPECT_EQ(from, 48);
  EXPECT_EQ(slew.update(choice_of(w, 48), from, w, 33'333'334ns).index, 48) << "arrived";
  // 25 points a second in 100 ms updates: 2.5 points each, the fraction carried over.
  core::GoalSlew quarter(25.0);
  from = 48;
  for (int k = 0; k < 4; ++k)
    from = quarter.update(choice_of(w, 16), from, w, 100ms).index;
  EXPECT_EQ(from, 58) << "10 steps on round the front toward the left in 400 ms";
  // Off, or nothing in use yet: the argmin at once.
  EXPECT_EQ(core::GoalSlew(0.0).update(choice_of(w, 48), 16, w, 1s).index, 48);
  EXPECT_EQ(core::GoalSlew(30.0).update(choice_of(w, 48), -1, w, 1s).index, 48);
}

TEST(GoalSlew, GoesOnlyThroughFreePointsAndJumpsWhereNeitherWayIsFree) {
  // A wall 0.9 m left of the person closes the points on their left.
  core::InteractiveSpace w(core::InteractiveSpaceConfig{});
  w.update(person_ahead(), core::Pose2{}, walled_room({0.9}));
  const auto c = w.candidates();
  ASSERT_FALSE(c[16].free);
  ASSERT_TRUE(c[0].free);
  ASSERT_TRUE(c[32].free);
  ASSERT_TRUE(c[48].free);
  // From ahead to behind: 32 steps either way, and the way past the left is closed: it goes
  // round the right (63, 62, ...), although the tie would go left.
  core::GoalSlew slew(30.0);
  EXPECT_EQ(slew.update(choice_of(w, 32), 0, w, 33'333'334ns).index, 63);
  // From a closed point it leaves at once, however slow the rate: the first closed point going
  // left from ahead, with its free neighbour toward the right.
  int edge = 1;
  while (c[static_cast<size_t>(edge)].free)
    ++edge;
  ASSERT_LT(edge, 16);
  core::GoalSlew slow(1.0);
  EXPECT_EQ(slow.update(choice_of(w, 32), edge, w, 10ms).index, edge - 1);
  // From a free point at that rate it waits for the step it is owed (the argmin stays ahead).
  EXPECT_EQ(slow.update(choice_of(w, 32), 0, w, 10ms).index, 0);
  // Walls on both sides: neither way round from ahead to behind is free; the argmin at once.
  core::InteractiveSpace both(core::InteractiveSpaceConfig{});
  both.update(person_ahead(), core::Pose2{}, walled_room({0.9, -0.9}));
  ASSERT_FALSE(both.candidates()[16].free);
  ASSERT_FALSE(both.candidates()[48].free);
  ASSERT_TRUE(both.candidates()[0].free);
  ASSERT_TRUE(both.candidates()[32].free);
  EXPECT_EQ(core::GoalSlew(30.0).update(choice_of(both, 32), 0, both, 33'333'334ns).index, 32);
}

TEST(InteractiveSpace, TurnInsideRaisesGOnTheSideThePersonTurnsToInProportion) {
  // The person 2 m ahead walking along +x, turning left at 1.5 rad/s: the points on their left
  // (y^h = b sin phi > 0) cost turn_inside * 1.5 * y^h more, those on the right nothing more.
  core::InteractiveSpaceConfig cfg;
  ASSERT_DOUBLE_EQ(cfg.turn_inside, 0.0) << "the paper's G by default";
  const core::Costmap open = walled_room({});
  core::InteractiveSpace paper(cfg);
  paper.update(person_ahead(), core::Pose2{}, open, {}, 1.5);
  cfg.turn_inside = 4.0;
  core::InteractiveSpace turning(cfg);
  turning.update(person_ahead(), core::Pose2{}, open, {}, 1.5);
  core::InteractiveSpace straight(cfg);
  straight.update(person_ahead(), core::Pose2{}, open, {}, 0.0);
  for (size_t i = 0; i < 64; ++i) {
    const double y_h = turning.point_in_person(i).y_m;
    EXPECT_NEAR(turning.candidates()[i].objective - paper.candidates()[i].objective,
                4.0 * 1.5 * std::max(0.0, y_h), 1e-9)
        << i;
    EXPECT_DOUBLE_EQ(straight.candidates()[i].objective, paper.candidates()[i].objective) << i;
  }
  EXPECT_NEAR(turning.candidates()[16].objective - paper.candidates()[16].objective,
              4.0 * 1.5 * 0.7, 1e-9)
      << "the left-hand point: b = 0.7 m to the left";
  // Turning right instead: the right-hand side pays.
  core::InteractiveSpace right(cfg);
  right.update(person_ahead(), core::Pose2{}, open, {}, -1.5);
  EXPECT_NEAR(right.candidates()[48].objective - paper.candidates()[48].objective, 4.0 * 1.5 * 0.7,
              1e-9);
  EXPECT_DOUBLE_EQ(right.candidates()[16].objective, paper.candidates()[16].objective);
}
