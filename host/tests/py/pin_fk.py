"""Forward kinematics of a URDF with pinocchio (a consumer rigctl did not write).

usage: pin_fk.py ROBOT.urdf Q.csv OUT.csv [FRAME]

Q.csv: a header of URDF joint names, one row per configuration, values in rad (m for
prismatic joints); joints not named stay at pinocchio's neutral configuration. OUT.csv: x,y,z of
FRAME (default tool0) in the root link's frame, mm, full precision.
"""
import csv
import math
import sys

import pinocchio as pin


def main() -> None:
    urdf, qcsv, out = sys.argv[1:4]
    frame = sys.argv[4] if len(sys.argv) > 4 else "tool0"
    model = pin.buildModelFromUrdf(urdf)
    data = model.createData()
    if not model.existFrame(frame):
        sys.exit(f"{urdf}: no frame {frame}")
    fid = model.getFrameId(frame)
    with open(qcsv, newline="") as f:
        rows = list(csv.reader(f))
    names, rows = rows[0], rows[1:]
    ids = []
    for n in names:
        if not model.existJointName(n):
            sys.exit(f"{urdf}: no joint {n}")
        ids.append(model.getJointId(n))
    with open(out, "w") as f:
        f.write("x,y,z\n")
        for r in rows:
            q = pin.neutral(model)
            for jid, v in zip(ids, r):
                j = model.joints[jid]
                v = float(v)
                if j.nq == 2:  # continuous joint: (cos, sin)
                    q[j.idx_q] = math.cos(v)
                    q[j.idx_q + 1] = math.sin(v)
                else:
                    q[j.idx_q] = v
            pin.framesForwardKinematics(model, data, q)
            p = data.oMf[fid].translation * 1000.0
            f.write(",".join(repr(float(x)) for x in p) + "\n")


if __name__ == "__main__":
    main()
