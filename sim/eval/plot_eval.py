#!/usr/bin/python3
"""Plots of a companion-eval output directory (Debian's python3-matplotlib; eval_samples.py).

    /usr/bin/python3 sim/eval/plot_eval.py OUT_DIR   (the system Python: Debian's matplotlib)

Writes into OUT_DIR/plots/:
  sides-<case>.png       where the robot was around the person (polar, share of moving time),
                         one panel per method (from trials.csv)
  trajectories-<case>.png  robot, person and chosen points of the first trial per method
  errors-<case>.png      e_x, e_y, e_theta over time (q^d - robot, robot frame), first trial
  sr-<group>.png         SR per method over a group's cases (crowds: pedestrians, with the
                         paper's proposed method; speeds: m/s; sizes: a x b; constrained:
                         the obstacles' clearance from the walk), when the directory has two
                         or more cases of the group
The trajectories and errors need the per-trial samples (companion-eval --samples).
"""
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import eval_samples  # noqa: E402

SIDES = ["front", "front_left", "left", "behind_left", "behind", "behind_right", "right",
         "front_right"]


def sides_plot(case, rows, out):
    methods = sorted({r["method"] for r in rows})
    fig, axes = plt.subplots(1, len(methods), subplot_kw={"projection": "polar"},
                             figsize=(3.2 * len(methods), 3.4), squeeze=False)
    for ax, method in zip(axes[0], methods):
        totals = [0.0] * 8
        for r in rows:
            if r["method"] == method:
                for i, s in enumerate(SIDES):
                    totals[i] += float(r["side_" + s])
        total = sum(totals) or 1.0
        angles = [i * math.pi / 4 for i in range(8)]  # 0 = ahead of the person, counter-clockwise
        ax.bar(angles, [100.0 * t / total for t in totals], width=math.pi / 4 * 0.9,
               color="#c0392b", alpha=0.7)
        ax.set_theta_zero_location("N")  # the person walks up the page
        ax.set_title(method, fontsize=10)
        ax.set_xticks(angles)
        ax.set_xticklabels(["front", "", "left", "", "behind", "", "right", ""], fontsize=8)
    fig.suptitle(f"{case}: the robot around the person (% of moving time)", fontsize=11)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


# The paper's crowd-density SR of its proposed method (reference/evaluation.md).
PAPER_CROWD_SR = {5: 81.0, 10: 65.0, 15: 33.0, 20: 26.0}
GROUPS = {  # case prefix -> (file name, x-axis label, value of the case's suffix)
    "crowd-": ("crowds", "pedestrians", int),
    "speed-": ("speeds", "person's walking speed (m/s)", float),
    "size-": ("sizes", "interaction space a x b (m)", str),
    "clutter-": ("constrained", "obstacles beside the walk, clearance (m)", float),
}


def success_rate(rows, case, method):
    """SR % of one method in one case; NaN (a gap in the line) when it did not run there."""
    picked = [r for r in rows if r["case"] == case and r["method"] == method]
    return 100.0 * sum(r["success"] == "1" for r in picked) / len(picked) if picked else math.nan


def sweep_plot(prefix, rows, out):
    """SR of every method over the cases of one group; False when there is nothing to sweep."""
    name, label, value = GROUPS[prefix]
    cases = sorted({r["case"] for r in rows if r["case"].startswith(prefix)},
                   key=lambda c: value(c[len(prefix):]) if value is not str else c)
    if len(cases) < 2:
        return False
    xs = list(range(len(cases)))
    fig, ax = plt.subplots(figsize=(5.6, 3.6))
    methods = sorted({r["method"] for r in rows})
    for method in methods:
        ax.plot(xs, [success_rate(rows, c, method) for c in cases], marker="o", label=method)
    if name == "crowds":
        paper = [PAPER_CROWD_SR.get(int(c[len(prefix):]), math.nan) for c in cases]
        ax.plot(xs, paper, "k--", marker="x", label="paper (RL + MPPI-CBF)")
    trials = max(sum(1 for r in rows if r["case"] == c and r["method"] == m)
                 for c in cases for m in methods)
    ax.set_xticks(xs)
    ax.set_xticklabels([c[len(prefix):] for c in cases])
    ax.set_xlabel(label)
    ax.set_ylabel("SR %")
    ax.set_ylim(-5, 105)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"{name}: success rate ({trials} trials per case and method)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return True


def first_samples(out_dir, case, rows):
    """The first trial's samples per method, with its world (walls, obstacles) when written."""
    picked = {}
    for r in rows:
        stem = os.path.join(out_dir, "samples", case, f"{r['method']}-{r['seed']}")
        if r["method"] not in picked and os.path.exists(stem + ".csv"):
            world_path = stem + "-world.csv"
            world = eval_samples.read_rows(world_path) if os.path.exists(world_path) else []
            picked[r["method"]] = (eval_samples.read_rows(stem + ".csv"), world)
    return picked


def draw_world(ax, world):
    for w in world:
        a, b, c, d = (float(w[k]) if w[k] else 0.0 for k in ("a", "b", "c", "d"))
        if w["kind"] == "segment":
            ax.plot([a, c], [b, d], color="#555555", linewidth=1.5)
        elif w["kind"] == "circle":
            ax.add_patch(plt.Circle((a, b), c, color="#555555", alpha=0.8))


def trajectories_plot(case, samples, out):
    fig, axes = plt.subplots(1, len(samples), figsize=(4.2 * len(samples), 4.2), squeeze=False)
    for ax, (method, (s, world)) in zip(axes[0], sorted(samples.items())):
        draw_world(ax, world)
        ax.plot([float(x["person_x_m"]) for x in s], [float(x["person_y_m"]) for x in s],
                color="#1f5fbf", label="person")
        ax.plot([float(x["robot_x_m"]) for x in s], [float(x["robot_y_m"]) for x in s],
                color="#c0392b", label="robot")
        g = [x for x in s if x["has_goal"] == "1" and x["active"] == "1"]
        ax.scatter([float(x["goal_x_m"]) for x in g[::3]], [float(x["goal_y_m"]) for x in g[::3]],
                   s=4, color="#2a9d3a", label="q^d")
        # The walk's extent (the world's walls may run far beyond it).
        xs = [float(x[k]) for x in s for k in ("person_x_m", "robot_x_m")]
        ys = [float(x[k]) for x in s for k in ("person_y_m", "robot_y_m")]
        if xs:
            ax.set_xlim(min(xs) - 3.0, max(xs) + 3.0)
            ax.set_ylim(min(ys) - 3.0, max(ys) + 3.0)
        ax.set_aspect("equal")
        ax.set_title(method, fontsize=10)
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    fig.suptitle(f"{case}: trajectories (first trial per method)", fontsize=11)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def errors_plot(case, samples, out):
    fig, axes = plt.subplots(3, 1, figsize=(9, 6.5), sharex=True)
    for method, (s, _) in sorted(samples.items()):
        tracked = eval_samples.tracking_errors(s)
        t = [x.t_s for x in tracked]
        for ax, v in zip(axes, ([x.ex_m for x in tracked], [x.ey_m for x in tracked],
                                [x.etheta_rad for x in tracked])):
            ax.plot(t, v, label=method, linewidth=1)
    for ax, name in zip(axes, ("e_x [m]", "e_y [m]", "e_theta [rad]")):
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, ncol=4)
    axes[2].set_xlabel("t [s]")
    fig.suptitle(f"{case}: tracking error q^d - robot in the robot frame (first trial)",
                 fontsize=11)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    out_dir = sys.argv[1]
    rows = eval_samples.read_rows(os.path.join(out_dir, "trials.csv"))
    plots = os.path.join(out_dir, "plots")
    os.makedirs(plots, exist_ok=True)
    written = []
    for case in sorted({r["case"] for r in rows}):
        case_rows = [r for r in rows if r["case"] == case]
        path = os.path.join(plots, f"sides-{case}.png")
        sides_plot(case, case_rows, path)
        written.append(path)
        samples = first_samples(out_dir, case, case_rows)
        if samples:
            for name, fn in (("trajectories", trajectories_plot), ("errors", errors_plot)):
                path = os.path.join(plots, f"{name}-{case}.png")
                fn(case, samples, path)
                written.append(path)
    for prefix, (name, _, _) in GROUPS.items():
        path = os.path.join(plots, f"sr-{name}.png")
        if sweep_plot(prefix, rows, path):
            written.append(path)
    for p in written:
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
