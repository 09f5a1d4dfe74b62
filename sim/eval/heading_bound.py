#!/usr/bin/python3
"""The smallest e_theta RMSE any base within the turn limits could reach on a trial's q^d.

    /usr/bin/python3 sim/eval/heading_bound.py [--config YAML] [--turn-window S] SAMPLES.csv...

SAMPLES.csv is a trial's sample file (companion-eval --samples: <out>/samples/<case>/<method>-
<seed>.csv). q^d's heading is the person's (the interactive space's points face the person's way),
so e_theta = person heading - robot heading, over the samples where the robot is active and has
a q^d, as companion-eval's metric (on the samples' 10 Hz grid rather than every 5 ms).

The bound: minimise the sum of (theta_k - r_k)^2 over robot headings theta that a base with
|omega| <= wz_max and |d omega / dt| <= angular_accel_max can turn through (the limits block of
the daemon's configuration, the simulated base's too), its initial heading and turn rate free. The
constraints are only the ones every such base satisfies between two samples (the rate at the
samples, and the change of rate and of heading over a step that the acceleration limit allows),
so the relaxed problem's optimum is below every real trajectory's: a lower bound, whatever the
controller. Solved as a sparse QP by cvxopt's interior-point solver (Debian's python3-cvxopt).

Printed per file: the robot's e_theta RMSE on the same grid, the bound, a heading law that
reacts to the person's heading without anticipating it (reactive_heading), and how much of the
robot's e_theta^2 and e_y^2 falls within S seconds (default 1) of the person turning faster
than 0.5 rad/s.
"""
import argparse
import math
import os
import sys

import cvxopt  # Debian's python3-cvxopt: the QP
import numpy as np

import eval_samples


def read_samples(path):
    """(t, robot theta, person theta, e_x, e_y, e_theta) over the tracked samples as arrays,
    the headings unwrapped."""
    s = eval_samples.tracking_errors(eval_samples.read_rows(path))
    if len(s) < 3:
        raise ValueError(f"{path}: fewer than 3 tracked samples")
    col = [np.array(c) for c in zip(*s)]
    return col[0], np.unwrap(col[1]), np.unwrap(col[2]), col[3], col[4], col[5]


def limit_rows(dt, wz_max, alpha_max):
    """The constraint rows of heading_bound as a sparse matrix's (rows, cols, values, row count)."""
    n, m = len(dt) + 1, len(dt)
    k = np.arange(m)
    pos = 2.0 / (alpha_max * dt**2)
    blocks = [  # (row within the block, column, value)
        (np.arange(n), n + np.arange(n), np.full(n, 1.0 / wz_max)),  # rate
        (np.r_[k, k], np.r_[n + k + 1, n + k],  # rate change
         np.r_[1.0 / (alpha_max * dt), -1.0 / (alpha_max * dt)]),
        (np.r_[k, k, k], np.r_[k + 1, k, n + k], np.r_[pos, -pos, -dt * pos]),  # heading change
        (np.r_[k, k], np.r_[k + 1, k], np.r_[1.0 / (wz_max * dt), -1.0 / (wz_max * dt)]),  # turn
    ]
    rows, cols, vals, offset = [], [], [], 0
    for r, c, v in blocks:
        rows.append(r + offset)
        cols.append(c)
        vals.append(v)
        offset += int(r.max()) + 1
    return np.concatenate(rows), np.concatenate(cols), np.concatenate(vals), offset


def heading_bound(t, ref, wz_max, alpha_max):
    """Minimum RMS of theta - ref over headings a base within the limits can follow (a QP).

    Variables x = (theta_0..n-1, omega_0..n-1). Constraints l <= A x <= u, every row scaled to
    its limit so that all are of order one:
      omega_k / wz_max                                   in [-1, 1]
      (omega_k+1 - omega_k) / (alpha_max dt)             in [-1, 1]
      (theta_k+1 - theta_k - omega_k dt) / (alpha_max dt^2 / 2)  in [-1, 1]
      (theta_k+1 - theta_k) / (wz_max dt)                in [-1, 1]
    (a base whose turn rate changes at most alpha_max turns at most that far beyond omega_k dt in
    a step, whichever way its acceleration varies within it; and never faster than wz_max).
    """
    n = len(t)
    dt = np.diff(t)
    if np.any(dt <= 0):
        raise ValueError("sample times must increase")
    rows, cols, vals, count = limit_rows(dt, wz_max, alpha_max)
    # -1 <= A x <= 1 as G x <= h: A's rows, then their negation.
    G = cvxopt.spmatrix(np.r_[vals, -vals].tolist(), np.r_[rows, rows + count].tolist(),
                        np.r_[cols, cols].tolist(), (2 * count, 2 * n))
    h = cvxopt.matrix(np.ones(2 * count))
    # Cost sum (theta - ref)^2 = x' P x / 2 + q' x + const: P = 2 on the theta block, q = -2 ref;
    # the time weights of the RMSE are the samples' (an even grid), so the plain sum.
    P = cvxopt.spmatrix(2.0, range(n), range(n), (2 * n, 2 * n))
    q = cvxopt.matrix(np.r_[-2.0 * ref, np.zeros(n)])
    options = {"show_progress": False, "abstol": 1e-9, "reltol": 1e-9, "feastol": 1e-9,
               "maxiters": 200}
    result = cvxopt.solvers.qp(P, q, G, h, options=options)
    if result["status"] != "optimal":
        raise RuntimeError(f"QP not solved ({result['status']})")
    x = np.array(result["x"]).ravel()
    return math.sqrt(np.mean((x[:n] - ref) ** 2)), x[:n]


def reactive_heading(t, ref, wz_max, alpha_max, step_s=0.005):
    """RMS of theta - ref for a heading law that sees only the person's heading now.

    Starting on the reference at rest, it turns toward the current reference (interpolated
    between the samples, no delay) as fast as it can still stop on it (omega = sqrt(2 alpha_max
    |e|), at most wz_max), its rate changing at most alpha_max, every step_s: a causal, feasible
    trajectory, so what a controller that does not anticipate the person's turn can reach, to
    set against the bound (which may turn before the person does). Not a proof that no causal
    law does better; the minimum-time answer to each heading as it comes.
    """
    theta, omega = ref[0], 0.0
    err = [0.0]
    now = t[0]
    for k in range(1, len(t)):
        while now < t[k] - 1e-9:
            dt = min(step_s, t[k] - now)
            e = float(np.interp(now, t, ref)) - theta
            want = math.copysign(min(wz_max, math.sqrt(2 * alpha_max * abs(e))), e)
            new_omega = omega + max(-alpha_max * dt, min(alpha_max * dt, want - omega))
            theta += 0.5 * (omega + new_omega) * dt
            omega = new_omega
            now += dt
        err.append(ref[k] - theta)
    return math.sqrt(np.mean(np.array(err) ** 2))


def turn_share(t, pth, err, window_s, turn_radps=0.5):
    """Share of sum(err^2) within window_s of the person turning faster than turn_radps."""
    rate = np.abs(np.gradient(pth, t))
    turning = t[rate > turn_radps]
    near = np.zeros(len(t), dtype=bool)
    for tt in turning:
        near |= np.abs(t - tt) <= window_s
    total = np.sum(err**2)
    return (np.sum(err[near] ** 2) / total if total > 0 else 0.0), np.mean(near)


def limits_from_config(path):
    import yaml  # Debian's python3-yaml

    with open(path) as f:
        cfg = yaml.safe_load(f) or {}
    limits = cfg.get("limits", {})
    return float(limits["wz_max_radps"]), float(limits["angular_accel_max_radps2"])


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--config", default=os.path.join(here, "..", "..", "config",
                                                     "companiond.yaml"))
    ap.add_argument("--turn-window", type=float, default=1.0)
    ap.add_argument("samples", nargs="+")
    args = ap.parse_args()
    wz_max, alpha_max = limits_from_config(args.config)
    if wz_max <= 0 or alpha_max <= 0:
        sys.exit(f"{args.config}: limits must be positive (wz {wz_max}, alpha {alpha_max})")
    print(f"limits: wz_max {wz_max} rad/s, angular_accel_max {alpha_max} rad/s^2")
    print("file | samples | e_theta robot | e_theta bound | reactive law | e_theta^2 near turns | "
          "e_y robot | e_y^2 near turns | time near turns")
    status = 0
    for path in args.samples:
        try:
            t, rth, pth, ex, ey, eth = read_samples(path)
            robot = math.sqrt(np.mean(eth**2))
            bound, _ = heading_bound(t, pth, wz_max, alpha_max)
            reactive = reactive_heading(t, pth, wz_max, alpha_max)
            share_th, near = turn_share(t, pth, eth, args.turn_window)
            share_y, _ = turn_share(t, pth, ey, args.turn_window)
            print(f"{path} | {len(t)} | {robot:.3f} | {bound:.3f} | {reactive:.3f} | "
                  f"{100 * share_th:.0f} % | {math.sqrt(np.mean(ey**2)):.3f} | "
                  f"{100 * share_y:.0f} % | {100 * near:.0f} %")
        except (OSError, ValueError, KeyError, RuntimeError) as e:
            print(f"{path}: {e}", file=sys.stderr)
            status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
