#!/usr/bin/python3
"""Where a run's tracking error comes from: each sample's e² put to the event it follows.

    sim/eval/error_sources.py DIR_OR_CSV... [--window-s 2] [--jump-m 0.3] [--turn-rad-s 0.5]
                              [--pedestrian-m 1.5] [--speed-change-mps2 A]

Reads the sample files of `companion-eval --samples` (the directories or single files; the
`-world.csv` files beside them are skipped) and sorts every active sample with a q^d into the
first event of this list that holds for it:

  q^d moved       within --window-s of q^d moving more than --jump-m from one sample to the next
                  in the person's frame: the selector chose another point of W (a point that
                  follows the person moves with their frame and does not count);
  person turning  within --window-s of the person's heading turning faster than --turn-rad-s
                  (q^d, fixed in their frame, swings round with them); only after the turning
                  sample, as for every event here: its error follows it (heading_bound.py's
                  turn_share, a share of e_theta² for its bound, counts the window both sides);
  speed change    only with --speed-change-mps2 A > 0: within --window-s of the person's speed
                  changing faster than A m/s² from one sample to the next (starting, stopping,
                  slowing to turn back: q^d, fixed in their frame, speeds up or brakes with them);
  pedestrian near a pedestrian within --pedestrian-m of the robot (the robot giving way);
  steady          none of these.

Prints a Markdown table: each event's share of the time and of the sums of e_x², e_y², e_θ², and
the RMSE within it; the first line gives the RMSE over every sample (pooled over the trials);
the last two the mean of the per-trial RMSEs (the tables' statistic) over every sample and over
the steady samples only. e as eval_samples.py computes it (the true poses;
e_θ against the person's heading). Standard library only.
"""
import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import eval_samples  # noqa: E402

EVENTS = ("q^d moved", "person turning", "pedestrian near", "steady")
SPEED_CHANGE = "speed change"  # between "person turning" and "pedestrian near", when asked for
EVENTS_WITH_SPEED = EVENTS[:2] + (SPEED_CHANGE,) + EVENTS[2:]


def goal_in_person_frame(row):
    """q^d in the person's frame (x along their heading), metres."""
    px, py, pth = (float(row[k]) for k in ("person_x_m", "person_y_m", "person_theta_rad"))
    dx, dy = float(row["goal_x_m"]) - px, float(row["goal_y_m"]) - py
    return (math.cos(pth) * dx + math.sin(pth) * dy, -math.sin(pth) * dx + math.cos(pth) * dy)


def person_speeds(rows):
    """The person's speed (m/s) at each row, from the step since the row before (0 at the
    first)."""
    out = [0.0]
    for a, b in zip(rows, rows[1:]):
        dt = float(b["t_s"]) - float(a["t_s"])
        step = math.hypot(float(b["person_x_m"]) - float(a["person_x_m"]),
                          float(b["person_y_m"]) - float(a["person_y_m"]))
        out.append(step / dt if dt > 0 else out[-1])
    return out


def classify(rows, window_s, jump_m, turn_rad_s, pedestrian_m, speed_change_mps2=0.0):
    """(event, TrackedSample) for each active row with a q^d, in time order. speed_change_mps2
    > 0 adds the event "speed change" (EVENTS_WITH_SPEED)."""
    rows = [r for r in rows if r["active"] == "1" and r["has_goal"] == "1"]
    errors = eval_samples.tracking_errors(rows)
    speeds = person_speeds(rows)
    last_jump_s = last_turn_s = last_speed_change_s = -math.inf
    previous = None
    out = []
    for i, (row, e) in enumerate(zip(rows, errors)):
        goal = goal_in_person_frame(row)
        if previous is not None:
            previous_goal, previous_theta, previous_t = previous
            if math.dist(goal, previous_goal) > jump_m:
                last_jump_s = e.t_s
            dt = e.t_s - previous_t
            turned = abs(eval_samples.wrap(e.person_theta_rad - previous_theta))
            if dt > 0 and turned / dt > turn_rad_s:
                last_turn_s = e.t_s
            if (speed_change_mps2 > 0 and i >= 2 and dt > 0 and
                    abs(speeds[i] - speeds[i - 1]) / dt > speed_change_mps2):
                last_speed_change_s = e.t_s
        previous = (goal, e.person_theta_rad, e.t_s)
        if e.t_s - last_jump_s <= window_s:
            event = EVENTS[0]
        elif e.t_s - last_turn_s <= window_s:
            event = EVENTS[1]
        elif e.t_s - last_speed_change_s <= window_s:
            event = SPEED_CHANGE
        elif float(row["nearest_pedestrian_m"]) < pedestrian_m:
            event = EVENTS[2]
        else:
            event = EVENTS[3]
        out.append((event, e))
    return out


def table(classified, events=EVENTS):
    """The Markdown table of error_sources for (event, TrackedSample) pairs, one row per event of
    `events`."""
    sums = {ev: [0, 0.0, 0.0, 0.0] for ev in events}
    for event, e in classified:
        s = sums[event]
        s[0] += 1
        s[1] += e.ex_m**2
        s[2] += e.ey_m**2
        s[3] += e.etheta_rad**2
    n = sum(s[0] for s in sums.values())
    if n == 0:
        return "no active samples with a q^d\n"
    total = [sum(s[k] for s in sums.values()) for k in range(1, 4)]
    lines = [f"{n} samples; RMSE e_x {math.sqrt(total[0] / n):.3f} m, e_y "
             f"{math.sqrt(total[1] / n):.3f} m, e_θ {math.sqrt(total[2] / n):.3f} rad", "",
             "| event | time % | e_x² % | e_y² % | e_θ² % | RMSE e_x / e_y / e_θ within |",
             "|---|---|---|---|---|---|"]
    for event in events:
        count, *sq = sums[event]
        if count == 0:
            lines.append(f"| {event} | 0.0 | 0.0 | 0.0 | 0.0 | - |")
            continue
        shares = " | ".join(f"{100 * q / t:.1f}" if t > 0 else "0.0" for q, t in zip(sq, total))
        rmse = " / ".join(f"{math.sqrt(q / count):.3f}" for q in sq)
        lines.append(f"| {event} | {100 * count / n:.1f} | {shares} | {rmse} |")
    return "\n".join(lines) + "\n"


def mean_trial_rmse(trials, event=None):
    """The mean over trials of each trial's RMSE (e_x, e_y, e_θ), as the tables average them,
    over the samples of `event` only (None: every sample); trials without such samples are left
    out. (None, 0) when there is none."""
    per_trial = []
    for classified in trials:
        es = [e for ev, e in classified if event is None or ev == event]
        if es:
            per_trial.append([math.sqrt(sum(getattr(e, k)**2 for e in es) / len(es))
                              for k in ("ex_m", "ey_m", "etheta_rad")])
    if not per_trial:
        return None, 0
    return [sum(r[k] for r in per_trial) / len(per_trial) for k in range(3)], len(per_trial)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("paths", nargs="+", help="sample directories or files")
    ap.add_argument("--window-s", type=float, default=2.0)
    ap.add_argument("--jump-m", type=float, default=0.3)
    ap.add_argument("--turn-rad-s", type=float, default=0.5)
    ap.add_argument("--pedestrian-m", type=float, default=1.5)
    ap.add_argument("--speed-change-mps2", type=float, default=0.0,
                    help="add the event 'speed change' at this acceleration (0: off)")
    args = ap.parse_args()
    for name in ("window_s", "jump_m", "turn_rad_s", "pedestrian_m", "speed_change_mps2"):
        value = getattr(args, name)
        if not math.isfinite(value) or value < 0:
            ap.error(f"--{name.replace('_', '-')} must be a finite number >= 0, not {value}")
    files = eval_samples.sample_files(args.paths)
    if not files:
        sys.exit(f"error_sources: no sample files in {' '.join(args.paths)}")
    trials = []
    for f in files:
        try:
            trials.append(classify(eval_samples.read_rows(f), args.window_s, args.jump_m,
                                   args.turn_rad_s, args.pedestrian_m, args.speed_change_mps2))
        except OSError as err:
            sys.exit(f"error_sources: {err}")
        except (KeyError, ValueError) as err:
            sys.exit(f"error_sources: {f}: not a companion-eval sample file ({err})")
    events = EVENTS_WITH_SPEED if args.speed_change_mps2 > 0 else EVENTS
    print(f"{len(files)} trials; " + table([c for t in trials for c in t], events), end="")
    for label, event in (("every sample", None), ("steady samples only", EVENTS[-1])):
        means, n = mean_trial_rmse(trials, event)
        if means is not None:
            print(f"\nMean of the per-trial RMSE ({label}, {n} trials): e_x {means[0]:.3f} m, "
                  f"e_y {means[1]:.3f} m, e_θ {means[2]:.3f} rad", end="")
    print()


if __name__ == "__main__":
    main()
