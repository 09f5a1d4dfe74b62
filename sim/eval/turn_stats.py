#!/usr/bin/python3
"""How sharply people turn: recorded pedestrians against the simulated person's walks.

    sim/eval/turn_stats.py [--period-s 0.4] [--walking-mps 0.5] [--window-s 2] [--acf-lags N]
                           SOURCE...

A SOURCE is a recorded-pedestrian file (`frame id x y`, the format of sim/data/pedestrians/, one
frame step taken as --period-s; every person's track, split where they are not observed for a
frame) or the sample files of `companion-eval --samples` (a directory, or files named one by one,
which make one row together; the person's true track of each trial; `-world.csv` files skipped).
Every track is looked at the same way, as the recorded files are made: positions every
--period-s (the samples taken at that period), the heading from the central difference of two
positions --period-s either side, counted only while the walker moves faster than
--walking-mps. Sampled this coarsely a quick turn reads slower than it was walked; both sources
read alike, which is the point of the comparison.

Prints a Markdown table, one row per source: the walking time, the median speed, the heading
rate's p50 / p90 / p99 and the share of the time above 0.5 and 1 rad/s, and the heading change
over the --window-s windows walked all through (p50 / p90 / p99, the share above 45 and 90
degrees). With --acf-lags N, a second table: the signed heading rate's autocorrelation (about
zero) at 1..N periods, over the pairs of rates walked all through, and the time constant tau of
a rate that fades as exp(-t / tau) read at the first lag whose two rates share no position (four
periods): how long a turn goes on, which is what a prediction of the person's turn should fade
with (human.prediction_turn_time_constant_s). Standard library only.
"""
import argparse
import collections
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import eval_samples  # noqa: E402

FRAMES_PER_GAP = 1.5  # a track is split where two observations are more than this many frames apart


def read_recorded(path):
    """Tracks of a `frame id x y` file: lists of (x, y), one observation per frame step."""
    people = collections.defaultdict(list)
    with open(path) as f:
        for number, line in enumerate(f, 1):
            cols = line.split()
            if not cols:
                continue
            bad = ValueError(f"{path}:{number}: expected 'frame id x y', got {line.strip()!r}")
            try:
                frame, pid, x, y = (float(c) for c in cols[:4]) if len(cols) >= 4 else [math.nan]*4
            except ValueError:
                raise bad from None
            if not all(map(math.isfinite, (frame, pid, x, y))):
                raise bad
            people[pid].append((frame, x, y))
    frames = sorted({o[0] for track in people.values() for o in track})
    steps = [b - a for a, b in zip(frames, frames[1:]) if b > a]
    step = min(steps) if steps else 1.0
    tracks = []
    for observations in people.values():
        observations.sort()
        current = []
        for k, (frame, x, y) in enumerate(observations):
            if k and frame - observations[k - 1][0] > FRAMES_PER_GAP * step:
                tracks.append(current)
                current = []
            current.append((x, y))
        tracks.append(current)
    return tracks


def read_samples(path, period_s):
    """The person's true track of one companion-eval sample file, every period_s."""
    track, next_s = [], 0.0
    for row in eval_samples.read_rows(path):
        t = float(row["t_s"])
        if t + 1e-6 >= next_s:
            track.append((float(row["person_x_m"]), float(row["person_y_m"])))
            next_s += period_s
    return track


def headings_of(track, period_s):
    """(heading rad, speed m/s) at every inner sample of a track: central differences."""
    headings = []
    for k in range(1, len(track) - 1):
        vx = (track[k + 1][0] - track[k - 1][0]) / (2 * period_s)
        vy = (track[k + 1][1] - track[k - 1][1]) / (2 * period_s)
        headings.append((math.atan2(vy, vx), math.hypot(vx, vy)))
    return headings


def turn_statistics(tracks, period_s, walking_mps, window_s):
    """Heading rates (rad/s) and window turns (rad) of tracks sampled every period_s."""
    rates, turns, speeds = [], [], []
    window = max(1, round(window_s / period_s))
    for track in tracks:
        headings = headings_of(track, period_s)
        walking = [speed > walking_mps for _, speed in headings]
        for k in range(len(headings) - 1):
            if walking[k] and walking[k + 1]:
                rates.append(abs(eval_samples.wrap(headings[k + 1][0] - headings[k][0])) / period_s)
                speeds.append(headings[k][1])
        for k in range(len(headings) - window):
            if all(walking[k:k + window + 1]):
                turns.append(abs(eval_samples.wrap(headings[k + window][0] - headings[k][0])))
    return rates, turns, speeds


# A heading rate spans four positions (two central differences), so rates this many periods apart
# share none: their correlation is the walker's, not the positions' noise made into both.
FIRST_INDEPENDENT_LAG = 4


def rate_autocorrelation(tracks, period_s, walking_mps, max_lag):
    """The signed heading rate's correlation about zero at lags 0..max_lag periods, over the
    pairs of rates walked all through: [(pairs, mean r_k r_k+m / mean r_k^2 over those pairs)].
    How long a turn goes on: a rate that fades as exp(-t / tau) keeps exp(-m period / tau)."""
    products = [[0.0, 0.0, 0] for _ in range(max_lag + 1)]  # sum r_k r_k+m, sum r_k^2, pairs
    for track in tracks:
        headings = headings_of(track, period_s)
        rates = [eval_samples.wrap(b[0] - a[0]) / period_s
                 if a[1] > walking_mps and b[1] > walking_mps else None
                 for a, b in zip(headings, headings[1:])]
        for m, p in enumerate(products):
            for a, b in zip(rates, rates[m:]):
                if a is not None and b is not None:
                    p[0] += a * b
                    p[1] += a * a
                    p[2] += 1
    return [(n, s / s2 if s2 > 0 else math.nan) for s, s2, n in products]


def fade_time_constant(correlation, lag_s):
    """tau of exp(-lag / tau) = correlation: inf when the rate keeps (>= 1), 0 when it is gone."""
    if math.isnan(correlation):
        return math.nan
    if correlation >= 1.0:
        return math.inf
    # Below 1e-9 the rate is gone (a correlation of zero sums to +-1e-17, not 0).
    return -lag_s / math.log(correlation) if correlation > 1e-9 else 0.0


def acf_row(label, correlations, period_s):
    cells = " | ".join("-" if math.isnan(c) else f"{c:.2f}" for _, c in correlations[1:])
    if len(correlations) > FIRST_INDEPENDENT_LAG:
        lag_s = FIRST_INDEPENDENT_LAG * period_s
        tau = fade_time_constant(correlations[FIRST_INDEPENDENT_LAG][1], lag_s)
        tau_cell = "-" if math.isnan(tau) else f"{tau:.2f}"
    else:
        tau_cell = "-"
    return f"| {label} | {correlations[0][0]} | {cells} | {tau_cell} |"


def percentile(values, q):
    """The nearest-rank percentile of values (q in 0..100): always one of the values, unlike
    statistics.quantiles, which interpolates (a share of turns at 0 and 2 rad/s would read 0.2)."""
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, max(0, math.ceil(q / 100 * len(ordered)) - 1))]


def row(label, rates, turns, speeds, period_s):
    if not rates or not turns:
        return f"| {label} | 0.0 | - | - | - | - | - | - | - | - |"

    def share(values, above):
        return 100.0 * sum(v > above for v in values) / len(values)
    deg = [math.degrees(t) for t in turns]
    return (f"| {label} | {len(rates) * period_s / 60:.1f} | {percentile(speeds, 50):.2f} | "
            f"{percentile(rates, 50):.2f} / {percentile(rates, 90):.2f} / "
            f"{percentile(rates, 99):.2f} | {share(rates, 0.5):.1f} | {share(rates, 1.0):.1f} | "
            f"{percentile(deg, 50):.0f} / {percentile(deg, 90):.0f} / {percentile(deg, 99):.0f} | "
            f"{share(deg, 45):.1f} | {share(deg, 90):.1f} |")


def sources(paths):
    """(label, kind, files): one per recorded file and per sample directory; the sample files
    named one by one (a shell glob) make one source together. World files are skipped."""
    out, loose = [], []
    for p in paths:
        if os.path.isdir(p):
            out.append((p, "samples", eval_samples.sample_files([p])))
        elif p.endswith(".csv"):
            loose += eval_samples.sample_files([p])
        else:
            out.append((p, "recorded", [p]))
    if loose:
        out.append((os.path.commonpath(loose) if len(loose) > 1 else loose[0], "samples", loose))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("paths", nargs="+", help="recorded-pedestrian files, sample directories/files")
    ap.add_argument("--period-s", type=float, default=0.4)
    ap.add_argument("--walking-mps", type=float, default=0.5)
    ap.add_argument("--window-s", type=float, default=2.0)
    ap.add_argument("--acf-lags", type=int, default=0,
                    help="also the heading rate's autocorrelation at 1..N periods (a second "
                         "table) and the time constant it implies")
    args = ap.parse_args()
    if args.acf_lags < 0:
        ap.error(f"--acf-lags must be >= 0, not {args.acf_lags}")
    for name in ("period_s", "walking_mps", "window_s"):
        value = getattr(args, name)
        if not math.isfinite(value) or value < 0 or (name != "walking_mps" and value == 0):
            ap.error(f"--{name.replace('_', '-')} must be a finite number > 0, not {value}")
    w = f"{args.window_s:g} s"
    print(f"| source | walking min | speed p50 m/s | heading rate p50 / p90 / p99 rad/s | "
          f"> 0.5 rad/s % | > 1 rad/s % | turn in {w} p50 / p90 / p99 deg | "
          f"> 45 deg in {w} % | > 90 deg in {w} % |")
    print("|---|---|---|---|---|---|---|---|---|")
    acf_rows = []
    for label, kind, files in sources(args.paths):
        if not files:
            sys.exit(f"turn_stats: no sample files in {label}")
        try:
            if kind == "recorded":
                tracks = read_recorded(files[0])
            else:
                tracks = [read_samples(f, args.period_s) for f in files]
        except OSError as err:
            sys.exit(f"turn_stats: {err}")
        except (KeyError, ValueError) as err:
            sys.exit(f"turn_stats: {label}: {err}")
        stats = turn_statistics(tracks, args.period_s, args.walking_mps, args.window_s)
        name = os.path.basename(label.rstrip("/")) if kind == "recorded" else label
        if kind == "samples":
            name += f" ({len(files)} trials)"
        print(row(name, *stats, args.period_s))
        if args.acf_lags:
            correlations = rate_autocorrelation(tracks, args.period_s, args.walking_mps,
                                                args.acf_lags)
            acf_rows.append(acf_row(name, correlations, args.period_s))
    if acf_rows:
        lags = " | ".join(f"{m * args.period_s:g} s" for m in range(1, args.acf_lags + 1))
        first = f"{FIRST_INDEPENDENT_LAG * args.period_s:g} s"
        print()
        print(f"| source | rate pairs | heading rate's autocorrelation at {lags} | "
              f"time constant from {first} (no shared positions) s |")
        print("|---|---|" + "---|" * args.acf_lags + "---|")
        print("\n".join(acf_rows))

if __name__ == "__main__":
    main()
