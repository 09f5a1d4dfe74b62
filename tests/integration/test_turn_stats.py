#!/usr/bin/python3
"""sim/eval/turn_stats.py on tracks written here, whose answers are known.

    /usr/bin/python3 tests/integration/test_turn_stats.py   (ctest: turn_stats_script)
"""
import math
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "sim", "eval", "turn_stats.py")
sys.path.insert(0, os.path.dirname(SCRIPT))
import turn_stats  # noqa: E402

PERIOD = 0.4


def arc(n, speed=1.0, rate=0.0, start=(0.0, 0.0)):
    """n positions every PERIOD of a walker at `speed` turning at `rate` rad/s."""
    out, (x, y), th = [], start, 0.0
    for _ in range(n):
        out.append((x, y))
        th += rate * PERIOD
        x, y = x + speed * PERIOD * math.cos(th), y + speed * PERIOD * math.sin(th)
    return out


class TurnStatistics(unittest.TestCase):
    def test_a_straight_walk_does_not_turn(self):
        rates, turns, speeds = turn_stats.turn_statistics([arc(30)], PERIOD, 0.5, 2.0)
        self.assertEqual(len(rates), 27)  # 28 inner samples, 27 steps between them
        self.assertEqual(len(turns), 28 - 5)  # a 2 s window spans 5 steps
        self.assertAlmostEqual(max(rates), 0.0, places=9)
        self.assertAlmostEqual(max(turns), 0.0, places=9)
        self.assertAlmostEqual(speeds[0], 1.0, places=9)

    def test_a_circle_turns_at_its_rate(self):
        rates, turns, _ = turn_stats.turn_statistics([arc(40, rate=0.5)], PERIOD, 0.5, 2.0)
        for r in rates:
            self.assertAlmostEqual(r, 0.5, places=9)
        for t in turns:
            self.assertAlmostEqual(t, 1.0, places=9)  # 0.5 rad/s for 2 s

    def test_standing_is_not_counted(self):
        slow = arc(30, speed=0.3, rate=2.0)
        rates, turns, _ = turn_stats.turn_statistics([slow], PERIOD, 0.5, 2.0)
        self.assertEqual((rates, turns), ([], []))

    def test_the_table_row_reads_the_shares(self):
        rates = [0.0] * 90 + [2.0] * 10  # 10 % above 1 rad/s
        turns = [0.0] * 80 + [math.radians(60)] * 15 + [math.radians(120)] * 5
        line = turn_stats.row("x", rates, turns, [1.0] * 100, PERIOD)
        self.assertEqual(line, "| x | 0.7 | 1.00 | 0.00 / 0.00 / 2.00 | 10.0 | 10.0 | "
                               "0 / 60 / 120 | 20.0 | 5.0 |")


def zigzag(corners, legs=10, angle=0.5):
    """Straight legs of `legs` steps, turning by +angle, -angle, ... at the `corners` corners."""
    out, x, y, th = [], 0.0, 0.0, 0.0
    for c in range(corners + 1):
        for _ in range(legs):
            out.append((x, y))
            x, y = x + PERIOD * math.cos(th), y + PERIOD * math.sin(th)
        th += angle if c % 2 == 0 else -angle
    out.append((x, y))
    return out


class RateAutocorrelation(unittest.TestCase):
    def test_a_circle_keeps_its_rate_at_every_lag(self):
        correlations = turn_stats.rate_autocorrelation([arc(40, rate=0.5)], PERIOD, 0.5, 5)
        self.assertEqual(correlations[0][0], 37)  # 38 inner samples, 37 rates
        self.assertEqual(correlations[5][0], 32)
        for _, c in correlations:
            self.assertAlmostEqual(c, 1.0, places=9)
        self.assertEqual(turn_stats.fade_time_constant(correlations[4][1], 1.6), math.inf)

    def test_corners_correlate_only_within_a_corner_and_with_the_next(self):
        # A corner at a vertex reads as two rates of angle / 2 (the central differences either
        # side of it); the next corner, 10 steps on, turns back.
        correlations = turn_stats.rate_autocorrelation([zigzag(6)], PERIOD, 0.5, 10)
        self.assertAlmostEqual(correlations[1][1], 0.5, places=9)
        for m in range(2, 9):
            self.assertAlmostEqual(correlations[m][1], 0.0, places=9)
        self.assertAlmostEqual(correlations[10][1], -1.0, places=9)
        self.assertEqual(turn_stats.fade_time_constant(correlations[4][1], 1.6), 0.0)

    def test_standing_walkers_and_short_tracks_leave_no_pairs(self):
        correlations = turn_stats.rate_autocorrelation(
            [arc(30, speed=0.3, rate=2.0), arc(3)], PERIOD, 0.5, 2)
        self.assertEqual([n for n, _ in correlations], [0, 0, 0])
        self.assertTrue(all(math.isnan(c) for _, c in correlations))
        self.assertTrue(math.isnan(turn_stats.fade_time_constant(math.nan, 1.6)))

    def test_the_time_constant_is_read_at_the_first_lag_without_shared_positions(self):
        self.assertAlmostEqual(turn_stats.fade_time_constant(math.exp(-1.0), 1.6), 1.6)
        line = turn_stats.acf_row("x", [(9, 1.0), (8, 0.5), (7, 0.3), (6, 0.2),
                                        (5, math.exp(-4.0)), (4, math.nan)], PERIOD)
        self.assertEqual(line, "| x | 9 | 0.50 | 0.30 | 0.20 | 0.02 | - | 0.40 |")
        self.assertEqual(turn_stats.acf_row("x", [(9, 1.0), (8, 0.5)], PERIOD),
                         "| x | 9 | 0.50 | - |")


class Files(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()

    def tearDown(self):
        self.tmp.cleanup()

    def write(self, name, text):
        path = os.path.join(self.tmp.name, name)
        with open(path, "w") as f:
            f.write(text)
        return path

    def test_recorded_tracks_split_where_a_person_is_not_seen(self):
        lines = [f"{10 * k}\t1.0\t{0.4 * k}\t0.0" for k in range(10)]
        lines += [f"{10 * k}\t1.0\t{0.4 * k}\t5.0" for k in range(20, 25)]  # seen again later
        lines += [f"{10 * k}\t2.0\t0.0\t{0.4 * k}" for k in range(5)]
        tracks = turn_stats.read_recorded(self.write("p.txt", "\n".join(lines) + "\n"))
        self.assertEqual(sorted(len(t) for t in tracks), [5, 5, 10])

    def test_a_bad_recorded_line_names_the_file_and_line(self):
        path = self.write("bad.txt", "0 1 0 0\n10 1 nan 0\n")
        with self.assertRaisesRegex(ValueError, r"bad.txt:2: expected 'frame id x y'"):
            turn_stats.read_recorded(path)
        with self.assertRaisesRegex(ValueError, r":1: expected"):
            turn_stats.read_recorded(self.write("short.txt", "0 1 0\n"))

    def test_the_command_reads_both_kinds_of_source(self):
        recorded = self.write("walk.txt", "".join(
            f"{10 * k} 1 {x:.6f} {y:.6f}\n" for k, (x, y) in enumerate(arc(40))))
        samples = os.path.join(self.tmp.name, "samples")
        os.mkdir(samples)
        rows = ["t_s,person_x_m,person_y_m"]  # every 0.1 s: resampled to 0.4 s
        for k in range(400):
            th = 0.625 * 0.1 * k
            rows.append(f"{0.1 * k:.3f},{1.6 * math.sin(th):.6f},{1.6 - 1.6 * math.cos(th):.6f}")
        with open(os.path.join(samples, "objective-1.csv"), "w") as f:
            f.write("\n".join(rows) + "\n")
        self.write("samples/objective-1-world.csv", "not read\n")
        out = subprocess.run([sys.executable, SCRIPT, recorded, samples], check=True,
                             capture_output=True, text=True).stdout.splitlines()
        self.assertEqual(len(out), 4)
        self.assertTrue(out[2].startswith("| walk.txt | "), out[2])
        self.assertIn(" 0.00 / 0.00 / 0.00 | 0.0 | 0.0 | 0 / 0 / 0 | 0.0 | 0.0 |", out[2])
        # A 1.6 m circle at 1 m/s: 0.625 rad/s, 72 degrees in 2 s.
        self.assertIn("samples (1 trials) | ", out[3])
        self.assertIn(" 0.63 / 0.63 / 0.63 | 100.0 | 0.0 | 72 / 72 / 72 | 100.0 | 0.0 |", out[3])

    def test_the_autocorrelation_table_follows_when_asked(self):
        recorded = self.write("zig.txt", "".join(
            f"{10 * k} 1 {x:.9f} {y:.9f}\n" for k, (x, y) in enumerate(zigzag(4))))
        out = subprocess.run([sys.executable, SCRIPT, "--acf-lags", "4", recorded], check=True,
                             capture_output=True, text=True).stdout.splitlines()
        self.assertEqual(len(out), 7)
        self.assertEqual(out[3], "")
        self.assertIn("autocorrelation at 0.4 s | 0.8 s | 1.2 s | 1.6 s | time constant from "
                      "1.6 s", out[4])
        self.assertEqual(out[6], "| zig.txt | 48 | 0.50 | 0.00 | 0.00 | 0.00 | 0.00 |")
        run = subprocess.run([sys.executable, SCRIPT, "--acf-lags", "-1", recorded],
                             capture_output=True, text=True)
        self.assertNotEqual(run.returncode, 0)
        self.assertIn("--acf-lags must be >= 0", run.stderr)

    def test_sample_files_named_one_by_one_make_one_row(self):
        rows = "t_s,person_x_m,person_y_m\n" + "".join(
            f"{0.1 * k:.3f},{0.1 * k:.3f},0\n" for k in range(100))
        files = [self.write(f"objective-{k}.csv", rows) for k in (1, 2)]
        files.append(self.write("objective-1-world.csv", "not read\n"))
        out = subprocess.run([sys.executable, SCRIPT] + files, check=True, capture_output=True,
                             text=True).stdout.splitlines()
        self.assertEqual(len(out), 3)
        self.assertTrue(out[2].startswith(f"| {self.tmp.name} (2 trials) | "), out[2])

    def test_a_missing_file_is_an_error_not_a_crash(self):
        run = subprocess.run([sys.executable, SCRIPT, os.path.join(self.tmp.name, "none.txt")],
                             capture_output=True, text=True)
        self.assertNotEqual(run.returncode, 0)
        self.assertIn("turn_stats:", run.stderr)
        self.assertNotIn("Traceback", run.stderr)


if __name__ == "__main__":
    unittest.main()
