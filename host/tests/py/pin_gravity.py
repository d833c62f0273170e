"""Generalised gravity of a URDF with pinocchio (a consumer rigctl did not write).

usage: pin_gravity.py ROBOT.urdf Q.csv OUT.csv

Q.csv: a header of URDF joint names, one row per configuration, values in rad (fixed base at the
root link, gravity -z of it, 9.81 m/s^2). OUT.csv: the same header, per row
`computeGeneralizedGravity` of every named joint (N.m), full precision.
"""
import csv
import sys

import pinocchio as pin


def main() -> None:
    urdf, qcsv, out = sys.argv[1:4]
    model = pin.buildModelFromUrdf(urdf)
    model.gravity.linear[:] = [0.0, 0.0, -9.81]
    data = model.createData()
    with open(qcsv, newline="") as f:
        rows = list(csv.reader(f))
    names, rows = rows[0], rows[1:]
    ids = []
    for n in names:
        if not model.existJointName(n):
            sys.exit(f"{urdf}: no joint {n}")
        j = model.joints[model.getJointId(n)]
        if j.nq != 1:
            sys.exit(f"{urdf}: joint {n} is not a revolute joint")
        ids.append(j)
    with open(out, "w") as f:
        f.write(",".join(names) + "\n")
        for r in rows:
            q = pin.neutral(model)
            for j, v in zip(ids, r):
                q[j.idx_q] = float(v)
            g = pin.computeGeneralizedGravity(model, data, q)
            f.write(",".join(repr(float(g[j.idx_v])) for j in ids) + "\n")


if __name__ == "__main__":
    main()
