#!/usr/bin/env python3
"""Reference timing for `rigctl calibrate --robot ur5 --base`: the same UR5 model fitted with
scipy.optimize.least_squares (benchmarks only; not a dependency of the project).

Model (as rigctl's `ur5` preset): Tx(base_x) Ty(base_y) Tz(base_z) Rx(base_rx) Ry(base_ry), then
per joint Rz(q + dth) Tz(d) Tx(a) Rx(al) (UR5 standard DH), then Tx Ty Tz(tool); the SMR
offset (0, 0.07, 31.0) mm is the nominal tool point. Fitted: the parameter set rigctl keeps
identifiable at its default threshold (the others stay nominal):
dth1..dth6, tool_dy, tool_dz, base_x, base_y, base_z, base_rx, base_ry, d2, d5, a1..a4, al1..al4.

Usage: python3 bench/ur5_scipy.py [DATA_DIR] [--rigctl PATH] [--runs N] [--jac 2-point|3-point|cs]
[--tol T]
(DATA_DIR defaults to ../shared/data/real/ur5_laser_tracker). Needs numpy and scipy (pip install
numpy scipy in a venv).

With --rigctl PATH (e.g. target/release/rigctl) the same run also times `rigctl calibrate --robot
ur5 --base` as a whole process (N runs, median wall time from spawn to exit, CSV reading and JSON
writing included), prints both parameter vectors (deg / mm), their largest difference and the
ratio rigctl whole process / scipy in-process.

The timed scipy fit uses --jac and --tol (defaults: scipy's 2-point Jacobian, tolerances 1e-8),
which stop short of the optimum along weakly seen directions (dth6 by 1.7e-4 deg). The
parameters are therefore also compared with a converged scipy fit made in the same run
(complex-step Jacobian, exact to round-off, tolerances 1e-15; timed separately, not in the
ratio): that is the comparison for "identical results".
"""
import argparse
import io
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

A = np.array([0, -425, -392.25, 0, 0, 0.0])
AL = np.radians([90, 0, 0, 90, -90, 0.0])
D = np.array([89.159, 0, 0, 109.15, 94.65, 82.3])
TOOL = np.array([0.0, 0.07, 31.0])
FITTED = (["dth%d" % i for i in range(1, 7)] + ["tool_dy", "tool_dz", "base_x", "base_y", "base_z", "base_rx", "base_ry", "d2", "d5"]
          + ["a%d" % i for i in range(1, 5)] + ["al%d" % i for i in range(1, 5)])


def load(path):
    lines = [l for l in open(path) if not l.startswith("#")]
    d = np.genfromtxt(io.StringIO("".join(lines)), delimiter=",", names=True)
    q = np.stack([d["q%d" % i] for i in range(1, 7)], 1)
    return np.radians(q), np.stack([d["x"], d["y"], d["z"]], 1)


def nominal():
    p = {"dth%d" % i: 0.0 for i in range(1, 7)}
    p.update({"d%d" % (i + 1): D[i] for i in range(6)})
    p.update({"a%d" % (i + 1): A[i] for i in range(6)})
    p.update({"al%d" % (i + 1): AL[i] for i in range(6)})
    p.update({"tool_dx": TOOL[0], "tool_dy": TOOL[1], "tool_dz": TOOL[2]})
    p.update({k: 0.0 for k in ["base_x", "base_y", "base_z", "base_rx", "base_ry"]})
    return p


def rot(axis, t):
    c, s = np.cos(t), np.sin(t)
    n = np.size(t)
    r = np.zeros((n, 3, 3), dtype=np.result_type(t, float))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    r[:, axis, axis] = 1
    r[:, i, i] = c
    r[:, j, j] = c
    r[:, i, j] = -s
    r[:, j, i] = s
    return r


def fk(p, q):
    n = len(q)
    R = rot(0, np.full(n, p["base_rx"])) @ rot(1, np.full(n, p["base_ry"]))
    dt = np.result_type(*[np.asarray(v) for v in p.values()], float)
    P = np.tile(np.array([p["base_x"], p["base_y"], p["base_z"]], dtype=dt), (n, 1))
    for i in range(6):
        k = str(i + 1)
        R = R @ rot(2, q[:, i] + p["dth" + k])
        P = P + R[:, :, 2] * p["d" + k] + R[:, :, 0] * p["a" + k]
        R = R @ rot(0, np.full(n, p["al" + k]))
    return P + R @ np.array([p["tool_dx"], p["tool_dy"], p["tool_dz"]])


def params_from(x):
    p = nominal()
    for name, v in zip(FITTED, x):
        p[name] = v
    return p


ANGLES = {n for n in FITTED if n.startswith(("dth", "al")) or n in ("base_rx", "base_ry")}


def run_rigctl(rigctl, data, runs):
    """Median wall time (s) of `rigctl calibrate` as a process, and its parameters."""
    times = []
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "cal.json"
        cmd = [rigctl, "calibrate", "--robot", "ur5", "--base", "--set", "tool_dy=0.07",
               "--set", "tool_dz=31.0", "--poses", str(data / "grid.csv"), "--json", str(out)]
        for _ in range(runs):
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
            times.append(time.perf_counter() - t0)
        params = json.load(open(out))["parameters"]
    return float(np.median(times)), params


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("data", nargs="?", default=str(Path(__file__).resolve().parents[2] / "shared/data/real/ur5_laser_tracker"))
    ap.add_argument("--rigctl")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--jac", default="2-point", help="2-point, 3-point or cs (complex step)")
    ap.add_argument("--tol", type=float, default=1e-8, help="scipy ftol = xtol = gtol")
    args = ap.parse_args()
    data = Path(args.data)
    qc, pc = load(data / "grid.csv")
    qv, pv = load(data / "random.csv")
    x0 = np.array([nominal()[n] for n in FITTED])

    def res(x, q, meas):
        return (fk(params_from(x), q) - meas).ravel()

    def cs_jac(x, q, meas):
        """Complex-step Jacobian: exact to round-off, so the fit converges like rigctl's."""
        h = 1e-30
        cols = []
        for k in range(len(x)):
            xc = x.astype(complex)
            xc[k] += 1j * h
            cols.append(res(xc, q, meas).imag / h)
        return np.stack(cols, 1)

    jac = cs_jac if args.jac == "cs" else args.jac

    def fit(jac_kind, tol):
        return least_squares(res, x0, args=(qc, pc), method="lm", x_scale="jac", jac=jac_kind,
                             ftol=tol, xtol=tol, gtol=tol)

    runs = []
    for _ in range(args.runs):
        t0 = time.perf_counter()
        sol = fit(jac, args.tol)
        runs.append(time.perf_counter() - t0)
    scipy_s = float(np.median(runs))
    mean = lambda e: np.linalg.norm(e.reshape(-1, 3), axis=1).mean()
    print("scipy least_squares (lm, %s Jacobian, tol %g): median %.1f ms over %d runs, %d evaluations"
          % (args.jac, args.tol, 1e3 * scipy_s, len(runs), sol.nfev))
    print("held-out mean: before %.4f mm, after %.4f mm" % (mean(res(x0, qv, pv)), mean(res(sol.x, qv, pv))))
    print("calibration mean after %.4f mm" % mean(sol.fun))
    if not args.rigctl:
        return
    t0 = time.perf_counter()
    conv = fit(cs_jac, 1e-15)
    conv_s = time.perf_counter() - t0
    rig_s, params = run_rigctl(args.rigctl, data, args.runs)

    def on_rigctl_branch(x):
        """scipy's parameters (deg / mm) on rigctl's branch of the dth6 half-turn ambiguity."""
        ours = {n: (np.degrees(v) if n in ANGLES else v) for n, v in zip(FITTED, x)}
        # The fit is unique only up to a half turn of the tool about joint 6's axis (dth6 + 180
        # deg with tool_dx, tool_dy negated moves no point): compare on rigctl's branch.
        if abs((ours["dth6"] - params.get("dth6", ours["dth6"]) + 180.0) % 360.0 - 180.0) > 90.0:
            ours["dth6"] -= 180.0 if ours["dth6"] > params["dth6"] else -180.0
            ours["tool_dy"] = -ours["tool_dy"]
        return ours

    timed, converged = on_rigctl_branch(sol.x), on_rigctl_branch(conv.x)
    print("%-8s %22s %22s %22s %10s" % ("param", "scipy (timed)", "scipy (converged)", "rigctl",
                                         "rigctl-conv"))
    worst_timed = worst_conv = 0.0
    for name in FITTED:
        r = params.get(name, float("nan"))
        worst_timed = max(worst_timed, abs(r - timed[name]))
        worst_conv = max(worst_conv, abs(r - converged[name]))
        print("%-8s %22.12f %22.12f %22.12f %10.2e" % (name, timed[name], converged[name], r,
                                                       r - converged[name]))
    print("largest parameter difference rigctl - scipy converged (cs Jacobian, tol 1e-15, %.0f ms, "
          "%d evaluations): %.2e (deg / mm); rigctl - scipy timed: %.2e"
          % (1e3 * conv_s, conv.nfev, worst_conv, worst_timed))
    print("rigctl calibrate, whole process: median %.1f ms over %d runs; scipy in-process %.1f ms; "
          "ratio 1/%.1f" % (1e3 * rig_s, args.runs, 1e3 * scipy_s, scipy_s / rig_s))


if __name__ == "__main__":
    main()
