#!/usr/bin/python3
"""How late the robot answers the person's turns, link by link.

    companion-eval ... --samples --sample-period-s 0.01 --out DIR
    sim/eval/turn_lag.py DIR_OR_CSV... [--max-lag-s 0.5] [--skip-s 1.0]

Reads the sample files of `companion-eval --samples` (directories or single files; the
`-world.csv` files beside them are skipped) and, over the active samples with a q^d (after the
first --skip-s of them), finds for each link of the chain the delay L in [-0.1, --max-lag-s]
that best explains the later signal as the earlier one delayed: y(t) ~ x(t - L), least squares
on a grid of the sample period. The links:

  person turn rate -> filter's      the true heading's rate against the daemon's person filter
                                    (its yaw-rate state: human.use_gyro, human.*_noise);
  filter's -> command               that against the command's turn rate (selection, MPPI, the
                                    repairs and limits: the controller's share);
  command -> robot turn rate        the command against the base's turn (its latency and
                                    acceleration limit);
  person heading -> robot heading   end to end (what e_theta sees: the person's heading is
                                    q^d's).

Rates are differences of the unwrapped headings over 50 ms (the simulated person's heading
steps every 50 ms). Prints a Markdown table, one row per
file and the mean over files, each cell "L s (rms at L / rms at 0)". Samples every 10 ms
(`--sample-period-s 0.01`) resolve a 10 ms delay; at the default 100 ms the grid is that coarse.
Standard library only.
"""
import argparse
import csv
import math
import os
import sys

LINKS = (
    ("person turn rate -> filter's", "person_rate", "est_rate"),
    ("filter's -> command", "est_rate", "cmd_rate"),
    ("command -> robot turn rate", "cmd_rate", "robot_rate"),
    ("person heading -> robot heading", "person_theta", "robot_theta"),
)


def unwrap(values):
    out, offset, prev = [], 0.0, None
    for v in values:
        if prev is not None:
            d = v - prev
            if d > math.pi:
                offset -= 2 * math.pi
            elif d < -math.pi:
                offset += 2 * math.pi
        out.append(v + offset)
        prev = v
    return out


def rate(t, x, half_width_s=0.025):
    """Differences over +-half_width_s (at least one sample; one-sided at the ends). The
    simulated person's heading is a staircase of 50 ms steps (sim::Trajectory::pose_at): a
    difference across one whole step is its turn rate, a 10 ms one a spike or nothing."""
    n = len(t)
    if n < 2:
        return [0.0] * n
    period = (t[-1] - t[0]) / (n - 1)
    h = max(1, int(round(half_width_s / period)))
    out = []
    for i in range(n):
        a, b = max(i - h, 0), min(i + h, n - 1)
        out.append((x[b] - x[a]) / (t[b] - t[a]) if t[b] > t[a] else 0.0)
    return out


def read_signals(path):
    """The active samples with a q^d and a person estimate: dict of equal-length lists."""
    rows = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            if r.get("active") != "1" or r.get("has_goal") != "1":
                continue
            try:
                est_theta = float(r["person_est_theta_rad"])
                est_rate = float(r["person_est_yaw_rate_radps"])
                vals = (float(r["t_s"]), float(r["person_theta_rad"]),
                        float(r["robot_theta_rad"]), est_theta, est_rate,
                        float(r["cmd_wz_radps"]))
            except (KeyError, ValueError):
                raise SystemExit(f"{path}: not a samples file with the filter's columns "
                                 "(companion-eval --samples from the thirty-ninth session on)")
            if all(math.isfinite(v) for v in vals):
                rows.append(vals)
    t = [r[0] for r in rows]
    person_theta = unwrap([r[1] for r in rows])
    robot_theta = unwrap([r[2] for r in rows])
    return {
        "t": t,
        "person_theta": person_theta,
        "robot_theta": robot_theta,
        "person_rate": rate(t, person_theta),
        "robot_rate": rate(t, robot_theta),
        "est_rate": [r[4] for r in rows],
        "cmd_rate": [r[5] for r in rows],
    }


def best_lag(t, x, y, period, max_lag, skip_s):
    """(lag, rms at lag, rms at 0) of y(t) ~ x(t - lag) over t >= t0 + skip_s, lags on the
    samples' own grid (a sample whose delayed partner was not recorded, inactive, is left out)."""
    key = [int(round(v / period)) for v in t]
    x_at = dict(zip(key, x))
    start = t[0] + skip_s
    idx = [i for i in range(len(t)) if t[i] >= start]

    def rms(k):
        e = [(y[i] - x_at[key[i] - k]) ** 2 for i in idx if key[i] - k in x_at]
        return math.sqrt(sum(e) / len(e)) if e else math.inf

    steps = range(int(round(-0.1 / period)), int(round(max_lag / period)) + 1)
    r_best, k_best = min((rms(k), k) for k in steps)
    return k_best * period, r_best, rms(0)


def sample_files(paths):
    for p in paths:
        if os.path.isdir(p):
            for root, _, files in sorted(os.walk(p)):
                for name in sorted(files):
                    if name.endswith(".csv") and not name.endswith("-world.csv"):
                        yield os.path.join(root, name)
        else:
            yield p


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("paths", nargs="+")
    ap.add_argument("--max-lag-s", type=float, default=0.5)
    ap.add_argument("--skip-s", type=float, default=1.0)
    a = ap.parse_args(argv)
    print("| file | " + " | ".join(name for name, _, _ in LINKS) + " |")
    print("|---|" + "---|" * len(LINKS))
    sums = [0.0] * len(LINKS)
    n = 0
    for path in sample_files(a.paths):
        s = read_signals(path)
        t = s["t"]
        if len(t) < 20:
            print(f"| {os.path.basename(path)} | too few active samples |")
            continue
        period = (t[-1] - t[0]) / (len(t) - 1)
        cells = []
        for k, (_, x, y) in enumerate(LINKS):
            lag, r_lag, r0 = best_lag(t, s[x], s[y], period, a.max_lag_s, a.skip_s)
            sums[k] += lag
            cells.append(f"{lag:.2f} s ({r_lag:.3f} / {r0:.3f})")
        n += 1
        print(f"| {os.path.basename(path)} | " + " | ".join(cells) + " |")
    if n == 0:
        print("no samples files", file=sys.stderr)
        return 1
    print(f"| mean of {n} | " + " | ".join(f"{v / n:.2f} s" for v in sums) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
