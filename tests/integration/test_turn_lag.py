#!/usr/bin/python3
"""sim/eval/turn_lag.py on samples written here, whose delays are known.

    /usr/bin/python3 tests/integration/test_turn_lag.py   (ctest: turn_lag_script)
"""
import math
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "sim", "eval", "turn_lag.py")
sys.path.insert(0, os.path.dirname(SCRIPT))
import turn_lag  # noqa: E402

PERIOD = 0.01
HEADER = ("t_s,robot_x_m,robot_y_m,robot_theta_rad,person_x_m,person_y_m,person_theta_rad,active,"
          "has_goal,goal_x_m,goal_y_m,side,pedestrians,nearest_pedestrian_x_m,"
          "nearest_pedestrian_y_m,nearest_pedestrian_m,cmd_vx_mps,cmd_vy_mps,plan_tracking_cost,"
          "plan_collision_cost,plan_barrier_cost,cmd_wz_radps,person_est_theta_rad,"
          "person_est_yaw_rate_radps")


def turn_rate(t):
    """A person who corners now and then: 1 rad/s for 0.8 s every 3 s, smooth edges."""
    phase = t % 3.0
    return 0.5 * (1 - math.cos(2 * math.pi * phase / 0.8)) if phase < 0.8 else 0.0


def headings(n, dt=0.001):
    """The heading at every sample i * PERIOD (i < n), integrated at dt."""
    out, theta, k, per = [], 0.0, 0, int(round(PERIOD / dt))
    for _ in range(n):
        out.append(theta)
        for _ in range(per):
            theta += turn_rate(k * dt) * dt
            k += 1
    return out


def write_samples(path, filter_lag, command_lag, robot_lag, n=1500):
    """The filter's rate `filter_lag` behind the person's, the command `command_lag` behind the
    filter, the robot's heading `robot_lag` behind the person's; headings wrapped."""
    with open(path, "w") as f:
        f.write(HEADER + "\n")
        walked = headings(n)
        theta = {i: walked[max(i, 0)] for i in range(-100, n)}
        for i in range(n):
            t = i * PERIOD
            robot = theta[i - round(robot_lag / PERIOD)]
            wrap = lambda a: math.atan2(math.sin(a), math.cos(a))  # noqa: E731
            est_rate = turn_rate(max(t - filter_lag, 0.0))
            cmd = turn_rate(max(t - filter_lag - command_lag, 0.0))
            f.write(f"{t:.3f},0,0,{wrap(robot + 3.0):.6f},1,0,{wrap(theta[i] + 3.0):.6f},1,1,"
                    f"0,0,4,0,nan,nan,nan,0,0,0,0,0,{cmd:.6f},{wrap(theta[i]):.6f},"
                    f"{est_rate:.6f}\n")


class TurnLag(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()

    def tearDown(self):
        self.tmp.cleanup()

    def test_each_links_delay_is_found(self):
        path = os.path.join(self.tmp.name, "objective-1.csv")
        write_samples(path, 0.05, 0.12, 0.2)
        s = turn_lag.read_signals(path)
        lags = [turn_lag.best_lag(s["t"], s[x], s[y], PERIOD, 0.5, 1.0)[0]
                for _, x, y in turn_lag.LINKS]
        self.assertAlmostEqual(lags[0], 0.05, delta=0.011)  # person -> filter
        self.assertAlmostEqual(lags[1], 0.12, delta=0.011)  # filter -> command
        # command -> robot: the robot's turn is the person's 0.2 s late, the command's 0.03 s
        self.assertAlmostEqual(lags[2], 0.03, delta=0.011)
        self.assertAlmostEqual(lags[3], 0.2, delta=0.011)  # heading, through the wrap at pi

    def test_no_delay_is_none_and_the_table_has_every_file(self):
        for name in ("objective-1.csv", "objective-2.csv"):
            write_samples(os.path.join(self.tmp.name, name), 0.0, 0.0, 0.0)
        with open(os.path.join(self.tmp.name, "objective-1-world.csv"), "w") as f:
            f.write("kind,a,b,c,d\n")
        out = subprocess.run([sys.executable, SCRIPT, self.tmp.name], check=True,
                             capture_output=True, text=True).stdout
        rows = [line for line in out.splitlines() if line.startswith("| objective")]
        self.assertEqual(len(rows), 2, out)
        self.assertIn("| mean of 2 | 0.00 s | 0.00 s | 0.00 s | 0.00 s |", out)

    def test_samples_without_the_filters_columns_are_a_clear_error(self):
        path = os.path.join(self.tmp.name, "old.csv")
        with open(path, "w") as f:
            f.write(",".join(HEADER.split(",")[:21]) + "\n")
            f.write("0.000," + ",".join(["0"] * 6) + ",1,1," + ",".join(["0"] * 12) + "\n")
        r = subprocess.run([sys.executable, SCRIPT, path], capture_output=True, text=True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("not a samples file with the filter's columns", r.stderr)


if __name__ == "__main__":
    unittest.main()
