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
controller. Solved as a QP by ADMM (the OSQP iteration, numpy only: Debian's python3-numpy).

Printed per file: the robot's e_theta RMSE on the same grid, the bound, a heading law that
reacts to the person's heading without anticipating it (reactive_heading), and how much of the
robot's e_theta^2 and e_y^2 falls within S seconds (default 1) of the person turning faster
than 0.5 rad/s.
"""
import argparse
import csv
import math
import os
import sys

import numpy as np


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def read_samples(path):
    """(t, robot theta, person theta, e_x, e_y) over the tracked samples, headings unwrapped."""
    t, rth, pth, ex, ey = [], [], [], [], []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            if row["active"] != "1" or row["has_goal"] != "1":
                continue
            rx, ry, rt = (float(row[k]) for k in ("robot_x_m", "robot_y_m", "robot_theta_rad"))
            dx = float(row["goal_x_m"]) - rx
            dy = float(row["goal_y_m"]) - ry
            t.append(float(row["t_s"]))
            rth.append(rt)
            pth.append(float(row["person_theta_rad"]))
            ex.append(math.cos(rt) * dx + math.sin(rt) * dy)
            ey.append(-math.sin(rt) * dx + math.cos(rt) * dy)
    if len(t) < 3:
        raise ValueError(f"{path}: fewer than 3 tracked samples")
    return (np.array(t), np.unwrap(np.array(rth)), np.unwrap(np.array(pth)), np.array(ex),
            np.array(ey))


def heading_bound(t, ref, wz_max, alpha_max, iterations=50000, tol=1e-6):
    """Minimum RMS of theta - ref over headings a base within the limits can follow (ADMM).

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
    rows = []
    for k in range(n):
        a = np.zeros(2 * n)
        a[n + k] = 1.0 / wz_max
        rows.append(a)
    for k in range(n - 1):
        a = np.zeros(2 * n)
        a[n + k + 1] = 1.0 / (alpha_max * dt[k])
        a[n + k] = -1.0 / (alpha_max * dt[k])
        rows.append(a)
        b = np.zeros(2 * n)
        s = 1.0 / (alpha_max * dt[k] ** 2 / 2)
        b[k + 1] = s
        b[k] = -s
        b[n + k] = -dt[k] * s
        rows.append(b)
        c = np.zeros(2 * n)
        c[k + 1] = 1.0 / (wz_max * dt[k])
        c[k] = -1.0 / (wz_max * dt[k])
        rows.append(c)
    A = np.array(rows)
    lo, hi = -np.ones(A.shape[0]), np.ones(A.shape[0])
    # Cost (theta - ref)^2 summed: P = 2 on the theta block, q = -2 ref; the time weights of the
    # RMSE are the samples' (an even grid), so the plain sum.
    P = np.zeros((2 * n, 2 * n))
    P[:n, :n] = 2.0 * np.eye(n)
    q = np.zeros(2 * n)
    q[:n] = -2.0 * ref
    rho, sigma, relax = 1.0, 1e-6, 1.6
    K = P + sigma * np.eye(2 * n) + rho * A.T @ A
    K_inv = np.linalg.inv(K)  # a few hundred samples: one dense inverse, then products

    def solve(b):
        return K_inv @ b

    x = np.concatenate([ref, np.gradient(ref, t)])
    z = np.clip(A @ x, lo, hi)
    y = np.zeros(A.shape[0])
    for _ in range(iterations):
        x_t = solve(sigma * x - q + A.T @ (rho * z - y))
        z_t = A @ x_t
        x = relax * x_t + (1 - relax) * x
        z_mix = relax * z_t + (1 - relax) * z
        z_new = np.clip(z_mix + y / rho, lo, hi)
        y = y + rho * (z_mix - z_new)
        z = z_new
        primal = np.max(np.abs(A @ x - z))
        dual = np.max(np.abs(P @ x + q + A.T @ y))
        if primal < tol and dual < tol * max(1.0, np.max(np.abs(q))):
            break
    else:
        raise RuntimeError(f"ADMM did not converge (primal {primal:.2e}, dual {dual:.2e})")
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
            t, rth, pth, ex, ey = read_samples(path)
            eth = np.array([wrap(a) for a in pth - rth])
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
