"""A simulated capture session for `rigctl poses`, written independently of rigctl's own
simulator: a robot moving between N poses with a dwell at each (quintic joint moves), its
continuous joint log (controller CSV, and a ROS 2 bag written with rosbags through
write_bag.py), and an instrument's continuous log at another rate, with a clock offset, noise,
settling oscillations after each stop, gross outliers and missing samples.

usage:
  capture_session.py joints OUT_DIR --n N --seed S [--limits "lo:hi,lo:hi,..."]
      writes OUT_DIR/joints.csv (t, q1..qk; 100 Hz, 0.001 deg steps), OUT_DIR/truth_joints.csv
      (the N poses and their dwell, joint clock), OUT_DIR/fk_in.csv (t,q1..qk: the N poses,
      then the true joints at every instrument sample) and OUT_DIR/session.json.
  capture_session.py instrument OUT_DIR FK_OUT.csv
      FK_OUT.csv = `rigctl fk` of fk_in.csv (x,y,z,...). Writes OUT_DIR/truth_points.csv (the
      poses' true points), OUT_DIR/points.csv (generic t,x,y,z), OUT_DIR/points_vicon.csv (a
      Vicon Nexus Trajectories export in a German locale: `;` and decimal commas) and adds to
      session.json what was injected.
"""
import json
import math
import random
import sys

JOINT_HZ = 100.0
INST_HZ = 120.0
DWELL_S = 2.5
MOVE_S = 2.0
LEAD_S = 1.5  # still at pose 1 before the first move, and at pose N after the last
OFFSET_S = -12.3456  # t_joint = t_instrument + OFFSET_S
NOISE_MM = 0.02
OUTLIER_SHARE = 0.01
MISSING_SHARE = 0.005


def quintic(u):
    u = min(max(u, 0.0), 1.0)
    return u * u * u * (10 - 15 * u + 6 * u * u)


def trajectory(poses):
    """(q(t), dwell list [(start, end)], duration) of the session, joint clock."""
    segs = []
    t = 0.0
    dwells = []
    for k, _ in enumerate(poses):
        dwell = LEAD_S + DWELL_S if k == 0 else DWELL_S
        if k == len(poses) - 1:
            dwell += LEAD_S
        dwells.append((t, t + dwell))
        t += dwell
        if k + 1 < len(poses):
            segs.append((t, t + MOVE_S, poses[k], poses[k + 1]))
            t += MOVE_S
    total = t

    def q(tt):
        for k, (a, b) in enumerate(dwells):
            if tt <= b:
                if tt >= a or k == 0:
                    return list(poses[k])
                s0, s1, qa, qb = segs[k - 1]
                s = quintic((tt - s0) / (s1 - s0))
                return [x + s * (y - x) for x, y in zip(qa, qb)]
        return list(poses[-1])

    return q, dwells, total


def joints_mode(out, n, seed, limits):
    rng = random.Random(seed)
    poses = [[rng.uniform(lo + 5, hi - 5) for lo, hi in limits] for _ in range(n)]
    q, dwells, total = trajectory(poses)
    k_j = len(limits)
    head = "t," + ",".join(f"q{i + 1}" for i in range(k_j))
    with open(f"{out}/joints.csv", "w") as f:
        f.write("# controller log: t (s), joints (deg)\n" + head + "\n")
        for i in range(int(total * JOINT_HZ) + 1):
            t = i / JOINT_HZ
            qs = [round(v, 3) for v in q(t)]
            f.write(f"{t:.4f}," + ",".join(f"{v:.3f}" for v in qs) + "\n")
    with open(f"{out}/truth_joints.csv", "w") as f:
        f.write("k,start,end," + ",".join(f"q{i + 1}" for i in range(k_j)) + "\n")
        for k, (p, (a, b)) in enumerate(zip(poses, dwells)):
            f.write(f"{k},{a:.6f},{b:.6f}," + ",".join(f"{v:.9f}" for v in p) + "\n")
    # the instrument covers the joint clock from -1.3 s to total + 1.1 s
    t_inst0 = -1.3 - OFFSET_S
    n_inst = int((total + 2.4) * INST_HZ)
    with open(f"{out}/fk_in.csv", "w") as f:
        f.write(head + "\n")
        for p in poses:
            f.write("0," + ",".join(f"{v:.12f}" for v in p) + "\n")
        for i in range(n_inst):
            ti = t_inst0 + i / INST_HZ
            f.write(f"{ti:.6f}," + ",".join(f"{v:.12f}" for v in q(ti + OFFSET_S)) + "\n")
    session = {
        "n": n, "joint_hz": JOINT_HZ, "inst_hz": INST_HZ, "offset_s": OFFSET_S,
        "noise_mm": NOISE_MM, "t_inst0": t_inst0, "n_inst": n_inst, "total_s": total,
        "dwells": dwells,
    }
    with open(f"{out}/session.json", "w") as f:
        json.dump(session, f)


def read_rows(path):
    with open(path) as f:
        lines = [l.strip() for l in f if l.strip() and not l.startswith("#")]
    return [list(map(float, l.split(","))) for l in lines[1:]]


def instrument_mode(out, fk_out):
    with open(f"{out}/session.json") as f:
        s = json.load(f)
    rng = random.Random(1234)
    rows = read_rows(fk_out)
    n = s["n"]
    truth, track = rows[:n], rows[n:]
    with open(f"{out}/truth_points.csv", "w") as f:
        f.write("k,x,y,z\n")
        for k, r in enumerate(truth):
            f.write(f"{k},{r[0]:.9f},{r[1]:.9f},{r[2]:.9f}\n")
    starts = [a for a, _ in s["dwells"][1:]]  # arrivals (joint clock)
    samples = []
    outliers = missing = 0
    for i, r in enumerate(track):
        ti = s["t_inst0"] + i / s["inst_hz"]
        tj = ti + s["offset_s"]
        p = [r[0], r[1], r[2]]
        # settling after each stop: a decaying 8 Hz oscillation of 0.3 mm
        for a in starts:
            if 0.0 <= tj - a < 1.0:
                amp = 0.3 * math.exp(-(tj - a) / 0.08) * math.sin(2 * math.pi * 8 * (tj - a))
                p = [p[0] + amp, p[1] - 0.5 * amp, p[2] + 0.3 * amp]
        p = [v + rng.gauss(0.0, s["noise_mm"]) for v in p]
        u = rng.random()
        if u < OUTLIER_SHARE:
            outliers += 1
            d = rng.uniform(5.0, 50.0)
            p[rng.randrange(3)] += d if rng.random() < 0.5 else -d
        elif u < OUTLIER_SHARE + MISSING_SHARE:
            missing += 1
            p = None
        samples.append((ti, p))
    with open(f"{out}/points.csv", "w") as f:
        f.write("# tracker log: t (s, the tracker's clock), x,y,z (mm)\nt,x,y,z\n")
        for ti, p in samples:
            cells = ",," if p is None else ",".join(f"{v:.5f}" for v in p)
            f.write(f"{ti:.6f},{cells}\n")
    # Vicon Nexus export (frames at INST_HZ from frame 1), German locale
    frame0 = round(s["t_inst0"] * s["inst_hz"])
    with open(f"{out}/points_vicon.csv", "w") as f:
        f.write("Trajectories;;;;\n")
        f.write(f"{int(s['inst_hz'])};;;;\n")
        f.write(";;Robot:SMR;;\n")
        f.write("Frame;Sub Frame;X;Y;Z\n")
        f.write(";;mm;mm;mm\n")
        for i, (_, p) in enumerate(samples):
            cells = ";;" if p is None else ";".join(f"{v:.5f}".replace(".", ",") for v in p)
            f.write(f"{frame0 + i};0;{cells}\n")
    # the Vicon file's clock: frame / rate
    vicon_offset = s["offset_s"] + s["t_inst0"] - frame0 / s["inst_hz"]
    s.update({"outliers": outliers, "missing": missing, "vicon_offset_s": vicon_offset})
    with open(f"{out}/session.json", "w") as f:
        json.dump(s, f)


def main():
    mode, out = sys.argv[1], sys.argv[2]
    if mode == "joints":
        args = dict(zip(sys.argv[3::2], sys.argv[4::2]))
        limits = [tuple(map(float, p.split(":"))) for p in args["--limits"].split(",")]
        joints_mode(out, int(args["--n"]), int(args["--seed"]), limits)
    else:
        instrument_mode(out, sys.argv[3])


if __name__ == "__main__":
    main()
