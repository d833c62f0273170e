#!/usr/bin/env python3
"""Reference timing for `rigctl calibrate --robot ur5 --base`: the same UR5 model fitted with
scipy.optimize.least_squares (benchmarks only; not a dependency of the project).

Model (as rigctl's `ur5` preset): Tx(base_x) Ty(base_y) Tz(base_z) Rx(base_rx) Ry(base_ry), then
per joint Rz(q + dth) Tz(d) Tx(a) Rx(al) (UR5 standard DH), then Tx Ty Tz(tool); the SMR
offset (0, 0.07, 31.0) mm is the nominal tool point. Fitted: the parameter set rigctl keeps
identifiable at its default threshold (the others stay nominal):
dth1..dth6, tool_dy, tool_dz, base_x, base_y, base_z, base_rx, base_ry, d2, d5, a1..a4, al1..al4.

Usage: python3 bench/ur5_scipy.py [DATA_DIR]   (default ../shared/data/real/ur5_laser_tracker)
Needs numpy and scipy (pip install numpy scipy in a venv).
"""
import io
import sys
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
    r = np.zeros((n, 3, 3))
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
    P = np.tile([p["base_x"], p["base_y"], p["base_z"]], (n, 1)).astype(float)
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


def main():
    data = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / "shared/data/real/ur5_laser_tracker"
    qc, pc = load(data / "grid.csv")
    qv, pv = load(data / "random.csv")
    x0 = np.array([nominal()[n] for n in FITTED])

    def res(x, q, meas):
        return (fk(params_from(x), q) - meas).ravel()

    runs = []
    for _ in range(5):
        t0 = time.perf_counter()
        sol = least_squares(res, x0, args=(qc, pc), method="lm", x_scale="jac")
        runs.append(time.perf_counter() - t0)
    mean = lambda e: np.linalg.norm(e.reshape(-1, 3), axis=1).mean()
    print("scipy least_squares (lm, 2-point Jacobian): median %.1f ms over %d runs, %d evaluations"
          % (1e3 * np.median(runs), len(runs), sol.nfev))
    print("held-out mean: before %.4f mm, after %.4f mm" % (mean(res(x0, qv, pv)), mean(res(sol.x, qv, pv))))
    print("calibration mean after %.4f mm" % mean(sol.fun))


if __name__ == "__main__":
    main()
