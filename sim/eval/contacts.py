#!/usr/bin/python3
"""Who moved into whom: every trial lost to a collision with a person, and how the robot moved.

    sim/eval/contacts.py OUT_DIR... [--toward-mps 0.05]

Reads companion-eval output directories (trials.csv and the samples of `--samples`), and for each
trial whose failure is a collision with a pedestrian or the person prints the robot's speed and
its velocity toward the one it touched over the last sample step before the contact (100 ms
samples; the pedestrian is the sample's nearest one, true positions). Above --toward-mps the
robot drove into them; otherwise they came to the robot (the simulated person and recorded
pedestrians do not walk into the robot, so with the defaults that means the robot closed the gap
first and stopped). Trials without samples are listed as such. Standard library only.
"""
import argparse
import csv
import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import eval_samples  # noqa: E402

COLLISION = re.compile(r"collision with (a pedestrian|the person) at t=([0-9.]+) s")


def contact(rows, t_contact_s, whom):
    """(robot speed, its velocity toward `whom`, centre distance) over the last sample step at or
    before the contact, from sample rows; None with fewer than two samples there."""
    before = [r for r in rows if float(r["t_s"]) <= t_contact_s + 1e-9]
    if len(before) < 2:
        return None
    a, b = before[-2], before[-1]
    dt = float(b["t_s"]) - float(a["t_s"])
    if dt <= 0:
        return None
    vx = (float(b["robot_x_m"]) - float(a["robot_x_m"])) / dt
    vy = (float(b["robot_y_m"]) - float(a["robot_y_m"])) / dt
    key = "person" if whom == "the person" else "nearest_pedestrian"
    dx = float(b[key + "_x_m"]) - float(b["robot_x_m"])
    dy = float(b[key + "_y_m"]) - float(b["robot_y_m"])
    dist = math.hypot(dx, dy)
    toward = (vx * dx + vy * dy) / dist if dist > 0 else 0.0
    return math.hypot(vx, vy), toward, dist


def contacts(out_dir):
    """One dict per trial of out_dir/trials.csv lost to a collision with a person."""
    found = []
    for trial in eval_samples.read_rows(os.path.join(out_dir, "trials.csv")):
        m = COLLISION.search(trial["failure"])
        if not m:
            continue
        whom, t_s = m.group(1), float(m.group(2))
        path = os.path.join(out_dir, "samples", trial["case"],
                            "{}-{}.csv".format(trial["method"], trial["seed"]))
        moved = contact(eval_samples.read_rows(path), t_s, whom) if os.path.exists(path) else None
        found.append({"case": trial["case"], "method": trial["method"], "seed": trial["seed"],
                      "scenario": trial["scenario"], "whom": whom, "t_s": t_s, "moved": moved})
    return found


def row(c, toward_mps):
    head = "| {} | {} | {} | {} | {} | {:.1f} |".format(
        c["case"], c["method"], c["seed"], c["scenario"], c["whom"], c["t_s"])
    if c["moved"] is None:
        return head + " - | - | - | no samples (run with --samples) |"
    speed, toward, dist = c["moved"]
    verdict = "the robot drove into them" if toward > toward_mps else "they came to the robot"
    return head + " {:.2f} | {:+.2f} | {:.2f} | {} |".format(speed, toward, dist, verdict)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dirs", nargs="+", help="companion-eval --out directories")
    ap.add_argument("--toward-mps", type=float, default=0.05,
                    help="the robot's velocity toward them above which it drove into them")
    args = ap.parse_args(argv)
    found = []
    for d in args.dirs:
        if not os.path.exists(os.path.join(d, "trials.csv")):
            print("contacts.py: {}: no trials.csv".format(d), file=sys.stderr)
            return 2
        try:
            found += contacts(d)
        except (KeyError, ValueError, csv.Error) as e:
            print("contacts.py: {}: not a companion-eval output ({})".format(d, e),
                  file=sys.stderr)
            return 2
    print("| case | method | seed | scenario | touched | t s | robot m/s | toward them m/s "
          "| centres m | |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for c in found:
        print(row(c, args.toward_mps))
    robot = sum(c["moved"] is not None and c["moved"][1] > args.toward_mps for c in found)
    print("\n{} contacts; the robot drove into them in {}.".format(len(found), robot))
    return 0

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
