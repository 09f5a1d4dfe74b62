#!/usr/bin/env python3
"""Draws a costmap snapshot of companion-eval --costmap-at (a map_server map: PGM + YAML) with
what the daemon knew then: the robot (red), the person (blue) and q^d (green), headings as
arrows, the cost threshold R as an orange contour, the obstacle cells old enough for the speed
limit toward obstacles to count (obstacle_ages, settled_s) in purple, the controller's best
plan's cost by term in the title. Needs Debian's python3-matplotlib and python3-yaml (run with
/usr/bin/python3).

    /usr/bin/python3 sim/eval/plot_costmap.py OUT/costmaps/random-objective-8-t9.5.yaml [PNG]
"""
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402


def read_pgm(path):
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(maxsplit=4)
    if parts[0] != b"P5" or int(parts[3]) != 255:
        raise SystemExit(f"{path}: not an 8-bit binary PGM")
    w, h = int(parts[1]), int(parts[2])
    pixels = np.frombuffer(parts[4][: w * h], dtype=np.uint8)
    if pixels.size != w * h:
        raise SystemExit(f"{path}: truncated ({pixels.size} of {w * h} pixels)")
    return pixels.reshape(h, w)


def arrow(ax, pose, colour, label):
    x, y, th = pose
    ax.plot(x, y, "o", color=colour, ms=8, label=label)
    ax.arrow(x, y, 0.4 * math.cos(th), 0.4 * math.sin(th), color=colour, width=0.02)


def main():
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    meta_path = sys.argv[1]
    with open(meta_path) as f:
        meta = yaml.safe_load(f)
    image = read_pgm(os.path.join(os.path.dirname(meta_path), meta["image"]))
    cost = (255.0 - image.astype(float)) / 2.55  # back to 0..100, top row = largest y
    res = float(meta["resolution"])
    ox, oy = float(meta["origin"][0]), float(meta["origin"][1])
    h, w = cost.shape
    extent = [ox, ox + w * res, oy, oy + h * res]
    fig, ax = plt.subplots(figsize=(8, 8))
    ax.imshow(cost, extent=extent, cmap="gray_r", vmin=0, vmax=100)
    xs = ox + (np.arange(w) + 0.5) * res
    ys = oy + (np.arange(h)[::-1] + 0.5) * res
    ax.contour(xs, ys, cost, levels=[float(meta.get("cost_threshold", 30))], colors="orange")
    ages = meta.get("obstacle_ages")
    if ages:  # the cells the speed limit toward obstacles counts: obstacles at least settled_s old
        age_px = read_pgm(os.path.join(os.path.dirname(meta_path), ages["image"])).astype(float)
        age_s = np.where(age_px < 255, (254.0 - age_px) * float(ages["step_s"]), -1.0)
        rows, cols = np.nonzero(age_s >= float(ages["settled_s"]))
        if rows.size:
            ax.plot(ox + (cols + 0.5) * res, oy + (h - rows - 0.5) * res, "s", color="purple",
                    ms=2, label=f"obstacle cells >= {float(ages['settled_s']):g} s old")
    arrow(ax, meta["robot"], "red", "robot")
    if meta.get("person"):
        arrow(ax, meta["person"], "blue", "person")
    if meta.get("goal"):
        arrow(ax, meta["goal"], "green", "q^d")
    for key, colour in (("predicted_person", "blue"), ("predicted_goal", "green")):
        path = meta.get(key) or []
        if path:
            ax.plot([p[0] for p in path], [p[1] for p in path], ":", marker=".", color=colour,
                    label=key.replace("_", " ") + " (1 s marks)")
    plan = meta.get("plan_cost")
    title = f"t = {meta['t_s']:.1f} s (odom frame)"
    if plan:
        title += (f"\nbest plan: tracking {plan['tracking']:.0f}, collision "
                  f"{plan['collision']:.0f}, barrier {plan['barrier']:.0f}")
    ax.set_title(title)
    ax.set_xlabel("x m")
    ax.set_ylabel("y m")
    ax.legend(loc="upper right")
    out = sys.argv[2] if len(sys.argv) > 2 else os.path.splitext(meta_path)[0] + ".png"
    fig.savefig(out, dpi=80)
    print(out)


if __name__ == "__main__":
    main()
