#!/usr/bin/python3
"""sim/eval/error_sources.py on sample files written here, whose answers are known.

    /usr/bin/python3 tests/integration/test_error_sources.py   (ctest: error_sources_script)
"""
import csv
import math
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "sim", "eval", "error_sources.py")
sys.path.insert(0, os.path.dirname(SCRIPT))
import error_sources  # noqa: E402

DT = 0.1
COLUMNS = ["t_s", "robot_x_m", "robot_y_m", "robot_theta_rad", "person_x_m", "person_y_m",
           "person_theta_rad", "active", "has_goal", "goal_x_m", "goal_y_m",
           "nearest_pedestrian_m"]


def walk(n=100, goal_in_person=None, heading=None, pedestrian_m=None, robot_offset=(0.0, 0.1),
         speed=None):
    """Rows of a person walking at speed(k) m/s (1 by default); q^d at goal_in_person(k) in
    their frame (1 m behind by default), the robot at q^d minus robot_offset in the person's
    frame, facing their way."""
    rows = []
    x = y = 0.0
    for k in range(n):
        th = 0.0 if heading is None else heading(k)
        v = 1.0 if speed is None else speed(k)
        x, y = x + DT * v * math.cos(th), y + DT * v * math.sin(th)
        gx, gy = (-1.0, 0.0) if goal_in_person is None else goal_in_person(k)
        c, s = math.cos(th), math.sin(th)
        goal = (x + c * gx - s * gy, y + s * gx + c * gy)
        ox, oy = robot_offset
        robot = (goal[0] - (c * ox - s * oy), goal[1] - (s * ox + c * oy))
        ped = 10.0 if pedestrian_m is None else pedestrian_m(k)
        rows.append({"t_s": f"{k * DT:.3f}", "robot_x_m": robot[0], "robot_y_m": robot[1],
                     "robot_theta_rad": th, "person_x_m": x, "person_y_m": y,
                     "person_theta_rad": th, "active": "1", "has_goal": "1", "goal_x_m": goal[0],
                     "goal_y_m": goal[1], "nearest_pedestrian_m": ped})
    return [{k: str(v) for k, v in r.items()} for r in rows]


def events(rows, **kw):
    args = dict(window_s=2.0, jump_m=0.3, turn_rad_s=0.5, pedestrian_m=1.5)
    args.update(kw)
    return [ev for ev, _ in error_sources.classify(rows, **args)]


class ErrorSources(unittest.TestCase):
    def test_a_steady_walk_is_steady_and_its_error_is_the_offset(self):
        classified = error_sources.classify(walk(), 2.0, 0.3, 0.5, 1.5)
        self.assertEqual({ev for ev, _ in classified}, {"steady"})
        for _, e in classified:
            self.assertAlmostEqual(e.ex_m, 0.0, places=9)
            self.assertAlmostEqual(e.ey_m, 0.1, places=9)
        self.assertIn("| steady | 100.0 | 0.0 | 100.0 | 0.0 | 0.000 / 0.100 / 0.000 |",
                      error_sources.table(classified))

    def test_q_d_moving_round_the_person_counts_for_the_window_after_it(self):
        # q^d goes from behind to the person's left at sample 50 (1.2 m in their frame).
        ev = events(walk(goal_in_person=lambda k: (-1.0, 0.0) if k < 50 else (0.0, 0.7)))
        self.assertEqual(ev[:50], ["steady"] * 50)
        self.assertEqual(ev[50:71], ["q^d moved"] * 21)  # t 5.0 .. 7.0 s
        self.assertEqual(ev[71:], ["steady"] * 29)

    def test_q_d_following_the_person_is_not_a_move(self):
        # The person walks 0.1 m a sample; q^d creeps out 0.02 m a sample in their frame.
        ev = events(walk(goal_in_person=lambda k: (-1.0 - 0.02 * k, 0.0)))
        self.assertEqual(set(ev), {"steady"})

    def test_a_turn_counts_while_the_person_turns_and_the_window_after(self):
        # 1 rad/s from sample 30 to 40 (1 rad).
        ev = events(walk(heading=lambda k: 0.1 * min(max(k - 30, 0), 10)))
        self.assertEqual(ev[:31], ["steady"] * 31)
        self.assertEqual(ev[31:61], ["person turning"] * 30)  # t 3.1 .. 6.0 s
        self.assertEqual(ev[61:], ["steady"] * 39)

    def test_a_turn_slower_than_the_threshold_is_steady(self):
        ev = events(walk(heading=lambda k: 0.04 * k))  # 0.4 rad/s
        self.assertEqual(set(ev), {"steady"})

    def test_the_first_event_of_the_list_wins(self):
        # q^d moves during the turn, with a pedestrian near throughout.
        ev = events(walk(heading=lambda k: 0.1 * min(max(k - 30, 0), 10),
                         goal_in_person=lambda k: (-1.0, 0.0) if k < 35 else (0.0, -0.7),
                         pedestrian_m=lambda k: 1.0))
        self.assertEqual(ev[31:35], ["person turning"] * 4)
        self.assertEqual(ev[35:56], ["q^d moved"] * 21)
        self.assertEqual(ev[56:61], ["person turning"] * 5)
        self.assertEqual(ev[61:], ["pedestrian near"] * 39)
        self.assertEqual(ev[:31], ["pedestrian near"] * 31)

    def test_a_stop_is_a_speed_change_only_when_asked_for(self):
        # Walking at 1 m/s, braking at 2 m/s² from sample 50 (0.2 m/s a sample) to a standstill
        # at sample 55, then standing until sample 99.
        stop = walk(speed=lambda k: max(0.0, 1.0 - 0.2 * max(0, k - 49)))
        self.assertEqual(set(events(stop)), {"steady"})
        labels = events(stop, speed_change_mps2=1.0)
        # The first change is seen at sample 50 (its step is 0.8 m/s, the one before 1.0 m/s);
        # the last at 54 (0.0 against 0.2); 2 s after it, sample 74, is the window's last.
        self.assertEqual(labels[:50], ["steady"] * 50)
        self.assertEqual(labels[50:75], ["speed change"] * 25)
        self.assertEqual(labels[75:], ["steady"] * 25)
        # Braking at 2 m/s² is not a change faster than 3 m/s².
        self.assertEqual(set(events(stop, speed_change_mps2=3.0)), {"steady"})
        # A turn at the same time comes first in the list.
        turning = walk(speed=lambda k: max(0.0, 1.0 - 0.2 * max(0, k - 49)),
                       heading=lambda k: 0.0 if k < 50 else 0.1 * (k - 49))
        self.assertEqual(events(turning, speed_change_mps2=1.0)[50:55], ["person turning"] * 5)
        text = error_sources.table(error_sources.classify(stop, 2.0, 0.3, 0.5, 1.5, 1.0),
                                   error_sources.EVENTS_WITH_SPEED)
        self.assertIn("| speed change | 25.0 | 0.0 | 25.0 | 0.0 | 0.000 / 0.100 / 0.000 |", text)

    def test_inactive_samples_and_samples_without_q_d_are_left_out(self):
        rows = walk(n=10)
        rows[2]["active"] = "0"
        rows[3]["has_goal"] = "0"
        self.assertEqual(len(error_sources.classify(rows, 2.0, 0.3, 0.5, 1.5)), 8)

    def test_the_table_splits_the_squares_by_event(self):
        # Error 0.1 m in y while steady, 0.3 m after q^d moves.
        rows = walk(n=40, goal_in_person=lambda k: (-1.0, 0.0) if k < 20 else (-1.0, 0.5))
        for k in range(20, 40):
            rows[k] = walk(n=40, goal_in_person=lambda _: (-1.0, 0.5),
                           robot_offset=(0.0, 0.3))[k]
        text = error_sources.table(error_sources.classify(rows, 2.0, 0.3, 0.5, 1.5))
        # 20 samples at 0.01 and 20 at 0.09: e_y² shares 10 % and 90 %.
        self.assertIn("| q^d moved | 50.0 | 0.0 | 90.0 | 0.0 | 0.000 / 0.300 / 0.000 |", text)
        self.assertIn("| steady | 50.0 | 0.0 | 10.0 | 0.0 | 0.000 / 0.100 / 0.000 |", text)
        self.assertIn("RMSE e_x 0.000 m, e_y 0.224 m", text)

    def test_the_tables_statistic_is_the_mean_of_each_trials_rmse(self):
        # Two steady trials, e_y 0.1 and 0.3 m: the mean of their RMSEs is 0.2 (pooled: 0.224).
        trials = [error_sources.classify(walk(robot_offset=(0.0, oy)), 2.0, 0.3, 0.5, 1.5)
                  for oy in (0.1, 0.3)]
        means, n = error_sources.mean_trial_rmse(trials)
        self.assertEqual(n, 2)
        self.assertAlmostEqual(means[1], 0.2, places=9)
        # A trial with no steady sample is left out of the steady mean.
        crowded = walk(n=10, pedestrian_m=lambda k: 1.0)
        trials.append(error_sources.classify(crowded, 2.0, 0.3, 0.5, 1.5))
        self.assertEqual(error_sources.mean_trial_rmse(trials)[1], 3)
        self.assertEqual(error_sources.mean_trial_rmse(trials, "steady")[1], 2)
        self.assertEqual(error_sources.mean_trial_rmse(trials[2:], "steady"), (None, 0))

    def test_the_command_reads_a_directory_and_skips_world_files(self):
        with tempfile.TemporaryDirectory() as d:
            for name, rows in (("objective-1.csv", walk()), ("objective-2.csv", walk(n=50))):
                with open(os.path.join(d, name), "w", newline="") as f:
                    w = csv.DictWriter(f, fieldnames=COLUMNS)
                    w.writeheader()
                    w.writerows(rows)
            with open(os.path.join(d, "objective-1-world.csv"), "w") as f:
                f.write("kind,x_m,y_m\nwall,0,0\n")
            out = subprocess.run([sys.executable, SCRIPT, d], capture_output=True, text=True,
                                 check=True).stdout
            asked = subprocess.run([sys.executable, SCRIPT, d, "--speed-change-mps2", "1"],
                                   capture_output=True, text=True, check=True).stdout
        self.assertTrue(out.startswith("2 trials; 150 samples;"), out)
        self.assertIn("| steady | 100.0 |", out)
        self.assertIn("Mean of the per-trial RMSE (steady samples only, 2 trials): e_x 0.000 m, "
                      "e_y 0.100 m", out)
        self.assertNotIn("speed change", out)
        self.assertIn("| speed change | 0.0 | 0.0 | 0.0 | 0.0 | - |", asked)

    def test_a_file_that_is_not_a_sample_file_is_a_clear_error(self):
        with tempfile.TemporaryDirectory() as d:
            bad = os.path.join(d, "objective-1.csv")
            with open(bad, "w") as f:
                f.write("a,b\n1,2\n")
            r = subprocess.run([sys.executable, SCRIPT, bad], capture_output=True, text=True)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("not a companion-eval sample file", r.stderr)
            r = subprocess.run([sys.executable, SCRIPT, d + "/none.csv"], capture_output=True,
                               text=True)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("none.csv", r.stderr)
            self.assertNotIn("Traceback", r.stderr)

    def test_a_threshold_that_is_not_a_distance_or_a_time_is_a_clear_error(self):
        for flag, value in (("--window-s", "-1"), ("--jump-m", "nan"), ("--turn-rad-s", "inf"),
                            ("--speed-change-mps2", "-2")):
            r = subprocess.run([sys.executable, SCRIPT, HERE, flag, value], capture_output=True,
                               text=True)
            self.assertEqual(r.returncode, 2, (flag, r.stderr))
            self.assertIn(f"{flag} must be a finite number >= 0", r.stderr)


if __name__ == "__main__":
    unittest.main()
