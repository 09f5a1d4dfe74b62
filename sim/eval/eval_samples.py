"""A trial's sample file (companion-eval --samples) read as tracking errors.

Shared by plot_eval.py (errors over time), heading_bound.py (the e_theta bound), error_sources.py
and turn_stats.py, so that all compute e = q^d - robot and find the sample files the same way.
Standard library only: importing it loads neither matplotlib nor numpy.
"""
import collections
import csv
import glob
import math
import os

TrackedSample = collections.namedtuple(
    "TrackedSample", "t_s robot_theta_rad person_theta_rad ex_m ey_m etheta_rad")


def wrap(angle_rad):
    """The angle in [-pi, pi)."""
    return (angle_rad + math.pi) % (2 * math.pi) - math.pi


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def sample_files(paths):
    """The trials' sample files of directories and files, without the -world.csv beside them."""
    files = []
    for p in paths:
        found = sorted(glob.glob(os.path.join(p, "*.csv"))) if os.path.isdir(p) else [p]
        files += [f for f in found if not f.endswith("-world.csv")]
    return files


def tracking_errors(rows):
    """One TrackedSample per row where the robot is active and has a q^d.

    e_x, e_y: q^d - robot in the robot's frame. e_theta: the person's heading - the robot's,
    wrapped (q^d faces the person's way; the samples carry the person's heading, the true one,
    where companion-eval's metric uses the chosen point's from the daemon's estimate).
    """
    out = []
    for row in rows:
        if row["active"] != "1" or row["has_goal"] != "1":
            continue
        rx, ry, rth = (float(row[k]) for k in ("robot_x_m", "robot_y_m", "robot_theta_rad"))
        pth = float(row["person_theta_rad"])
        dx, dy = float(row["goal_x_m"]) - rx, float(row["goal_y_m"]) - ry
        out.append(TrackedSample(float(row["t_s"]), rth, pth,
                                 math.cos(rth) * dx + math.sin(rth) * dy,
                                 -math.sin(rth) * dx + math.cos(rth) * dy, wrap(pth - rth)))
    return out
