#!/usr/bin/python3
"""sim/eval/heading_bound.py on sample files written here, whose answers are known.

    /usr/bin/python3 tests/integration/test_heading_bound.py   (ctest: heading_bound_script)
"""
import csv
import math
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "sim", "eval", "heading_bound.py")
sys.path.insert(0, os.path.dirname(SCRIPT))
import heading_bound  # noqa: E402

import numpy as np  # noqa: E402

WZ_MAX, ALPHA_MAX = 2.0, 3.0
DT = 0.1
COLUMNS = ["t_s", "robot_x_m", "robot_y_m", "robot_theta_rad", "person_x_m", "person_y_m",
           "person_theta_rad", "active", "has_goal", "goal_x_m", "goal_y_m"]


def write_samples(path, person_theta, robot_theta=None, active=None):
    """A sample file: the person standing at (1, 0) with the given headings, q^d on them."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for k, pth in enumerate(person_theta):
            rth = 0.0 if robot_theta is None else robot_theta[k]
            on = 1 if active is None else active[k]
            w.writerow([f"{k * DT:.3f}", 0, 0, rth, 1, 0, pth, on, on, 1, 0])


def step_reference(n=101, size=math.pi / 2):
    """The person's heading jumps by `size` half way: a turn no base can follow."""
    return np.array([0.0 if k < n // 2 else size for k in range(n)])


def bang_bang(n, size):
    """A heading the limits allow through the step: accelerate, cruise, brake, centred on it."""
    t_acc = WZ_MAX / ALPHA_MAX
    d_acc = 0.5 * ALPHA_MAX * t_acc**2
    t_cruise = max(0.0, (size - 2 * d_acc) / WZ_MAX)
    total = 2 * t_acc + t_cruise
    start = (n // 2) * DT - total / 2
    out = []
    for k in range(n):
        s = k * DT - start
        if s <= 0:
            out.append(0.0)
        elif s < t_acc:
            out.append(0.5 * ALPHA_MAX * s**2)
        elif s < t_acc + t_cruise:
            out.append(d_acc + WZ_MAX * (s - t_acc))
        elif s < total:
            r = total - s
            out.append(size - 0.5 * ALPHA_MAX * r**2)
        else:
            out.append(size)
    return np.array(out)


class HeadingBound(unittest.TestCase):
    def test_a_heading_within_the_limits_is_followed_exactly(self):
        # A sway of 0.5 rad at 1.2 rad/s: rate 0.6 rad/s, acceleration 0.72 rad/s^2.
        t = np.arange(200) * DT
        ref = 0.5 * np.sin(1.2 * t)
        bound, theta = heading_bound.heading_bound(t, ref, WZ_MAX, ALPHA_MAX)
        self.assertLess(bound, 1e-3)
        self.assertLess(np.max(np.abs(theta - ref)), 5e-3)

    def test_a_sudden_turn_costs_more_than_the_turn_rate_alone_and_less_than_a_real_turn(self):
        n = 101
        ref = step_reference(n)
        t = np.arange(n) * DT
        bound, theta = heading_bound.heading_bound(t, ref, WZ_MAX, ALPHA_MAX)
        # The same problem with no acceleration limit to speak of: the turn rate's alone.
        rate_only, _ = heading_bound.heading_bound(t, ref, WZ_MAX, 1e4)
        feasible = math.sqrt(np.mean((bang_bang(n, math.pi / 2) - ref) ** 2))
        # The turn rate alone allows a ramp through the step's middle (error size / 2 - WZ_MAX
        # |tau| for |tau| <= size / (2 WZ_MAX): 0.126 rad RMS over these 10 s in continuous
        # time); the acceleration limit costs a little more (the S-curve that replaces the ramp
        # is ~2 % worse on a step: 0.128 against 0.125 rad).
        self.assertGreater(rate_only, 0.10)
        self.assertGreater(bound, rate_only + 0.0015)
        self.assertLessEqual(bound, feasible + 1e-4)
        # and the bound's heading keeps the limits (up to the solver's tolerance)
        omega = np.diff(theta) / DT
        self.assertLess(np.max(np.abs(omega)), WZ_MAX * (1 + 0.5 * DT * ALPHA_MAX / WZ_MAX) + 1e-3)

    def test_reacting_without_anticipation_costs_more_than_the_bound(self):
        n = 101
        ref = step_reference(n)
        t = np.arange(n) * DT
        bound, _ = heading_bound.heading_bound(t, ref, WZ_MAX, ALPHA_MAX)
        reactive = heading_bound.reactive_heading(t, ref, WZ_MAX, ALPHA_MAX)
        # The reactive law starts turning only at the step: the whole turn is error.
        self.assertGreater(reactive, 1.5 * bound)
        # ... and on a heading it can follow it has (almost) none.
        sway = 0.5 * np.sin(1.2 * t)
        self.assertLess(heading_bound.reactive_heading(t, sway, WZ_MAX, ALPHA_MAX), 0.05)

    def test_the_command_reads_sample_files_and_reports_the_robots_error_beside_the_bound(self):
        with tempfile.TemporaryDirectory() as d:
            cfg = os.path.join(d, "limits.yaml")
            with open(cfg, "w") as f:
                f.write(f"limits:\n  wz_max_radps: {WZ_MAX}\n"
                        f"  angular_accel_max_radps2: {ALPHA_MAX}\n")
            n = 101
            ref = step_reference(n)
            robot = bang_bang(n, math.pi / 2)
            good = os.path.join(d, "objective-1.csv")
            # The first 10 samples inactive: not tracked, so not counted.
            write_samples(good, ref, robot, active=[0] * 10 + [1] * (n - 10))
            short = os.path.join(d, "objective-2.csv")
            write_samples(short, [0.0, 0.0])
            out = subprocess.run([sys.executable, SCRIPT, "--config", cfg, good, short],
                                 capture_output=True, text=True, timeout=120)
            self.assertEqual(out.returncode, 1)  # the short file is an error, counted as one
            self.assertIn("objective-2.csv: fewer than 3 tracked samples", out.stderr)
            row = [line for line in out.stdout.splitlines() if line.startswith(good)]
            self.assertEqual(len(row), 1)
            cells = [c.strip() for c in row[0].split("|")]
            self.assertEqual(cells[1], str(n - 10))
            robot_rms = math.sqrt(np.mean((ref[10:] - robot[10:]) ** 2))
            self.assertAlmostEqual(float(cells[2]), robot_rms, places=3)
            self.assertLessEqual(float(cells[3]), float(cells[2]))
            self.assertGreater(float(cells[3]), 0.02)

    def test_a_config_without_the_limits_is_an_error(self):
        with tempfile.TemporaryDirectory() as d:
            cfg = os.path.join(d, "bad.yaml")
            with open(cfg, "w") as f:
                f.write("limits:\n  wz_max_radps: 0\n  angular_accel_max_radps2: 3\n")
            path = os.path.join(d, "s.csv")
            write_samples(path, step_reference())
            out = subprocess.run([sys.executable, SCRIPT, "--config", cfg, path],
                                 capture_output=True, text=True, timeout=60)
            self.assertNotEqual(out.returncode, 0)
            self.assertIn("limits must be positive", out.stderr)


if __name__ == "__main__":
    unittest.main()
