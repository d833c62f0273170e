#!/usr/bin/env python3
"""Independent safety check of a `rigctl plan` output with pinocchio + coal (hpp-fcl).

    check_plan_safety.py URDF SRDF PACKAGE_DIR PLAN.csv JOINT,NAMES TABLE_Z_MM STEP_DEG [TRAJ.yaml]

Loads the URDF with its collision meshes (the meshes themselves, as BVH models), locks every
joint that is not in JOINT,NAMES at its neutral value, checks every pair of geometries of
different joints except the SRDF's disabled pairs, and a half-space below z = TABLE_Z_MM (m
in pinocchio) against every geometry not fixed to the base. Checks each planned pose (the
plan's order) and the straight joint-space segments between consecutive poses at STEP_DEG,
every frame origin above the table, and the joint margins. With TRAJ.yaml (the plan's
JointTrajectory, what a robot drives) the segments are those between its consecutive points
(via points included) instead, and its standstills must be the CSV's poses in order. Prints
one JSON object.
"""
import csv
import json
import math
import sys

import numpy as np
import pinocchio as pin
import coal


def trajectory_points(path, rmodel, idx):
    """The `positions:` of a JointTrajectory YAML (rad), as configurations of `rmodel`."""
    out = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if line.startswith("- positions: ["):
                vals = [float(v) for v in line[len("- positions: ["):-1].split(",")]
                q = pin.neutral(rmodel)
                for j, v in zip(idx, vals):
                    q[rmodel.joints[j].idx_q] = v
                out.append(q)
    return out


def main():
    urdf, srdf, pkg, plan_csv, names, table_z_mm, step_deg = sys.argv[1:8]
    traj = sys.argv[8] if len(sys.argv) > 8 else None
    names = names.split(",")
    table_z = float(table_z_mm) / 1000.0
    step = math.radians(float(step_deg))
    model, cmodel, _ = pin.buildModelsFromUrdf(urdf, package_dirs=[pkg])
    lock = [model.getJointId(n) for n in model.names[1:] if n not in names]
    rmodel, rcmodel = pin.buildReducedModel(model, cmodel, lock, pin.neutral(model))
    rcmodel.addAllCollisionPairs()
    pin.removeCollisionPairs(rmodel, rcmodel, srdf)
    n_self = len(rcmodel.collisionPairs)
    table = pin.GeometryObject(
        "table", 0, 0, pin.SE3(np.eye(3), np.array([0.0, 0.0, table_z])),
        coal.Halfspace(np.array([0.0, 0.0, 1.0]), 0.0))
    t_id = rcmodel.addGeometryObject(table)
    n_table = 0
    for g in range(len(rcmodel.geometryObjects) - 1):
        if rcmodel.geometryObjects[g].parentJoint != 0:
            rcmodel.addCollisionPair(pin.CollisionPair(g, t_id))
            n_table += 1
    data, cdata = rmodel.createData(), pin.GeometryData(rcmodel)
    idx = [rmodel.getJointId(n) for n in names]
    lower = rmodel.lowerPositionLimit
    upper = rmodel.upperPositionLimit

    def q_of(deg):
        q = pin.neutral(rmodel)
        for j, v in zip(idx, deg):
            q[rmodel.joints[j].idx_q] = math.radians(v)
        return q

    def check(q):
        """(collision pair names or None, frames below the table)."""
        hit = pin.computeCollisions(rmodel, data, rcmodel, cdata, q, True)
        pair = None
        if hit:
            for k, r in enumerate(cdata.collisionResults):
                if r.isCollision():
                    p = rcmodel.collisionPairs[k]
                    pair = (rcmodel.geometryObjects[p.first].name,
                            rcmodel.geometryObjects[p.second].name)
                    break
        pin.updateFramePlacements(rmodel, data)
        low = [rmodel.frames[f].name for f in range(len(rmodel.frames))
               if rmodel.frames[f].parentJoint != 0
               and data.oMf[f].translation[2] < table_z - 1e-9]
        return pair, low

    with open(plan_csv, newline="") as f:
        rows = list(csv.reader(f))
    poses = [[float(x) for x in r[:len(names)]] for r in rows[1:]]
    out = {"poses": len(poses), "self_pairs": n_self, "table_pairs": n_table,
           "pose_collisions": [], "segment_collisions": [], "below_table": [],
           "segment_points": 0, "min_margin_deg": math.inf}
    for k, p in enumerate(poses):
        q = q_of(p)
        for j in idx:
            i = rmodel.joints[j].idx_q
            m = min(q[i] - lower[i], upper[i] - q[i])
            out["min_margin_deg"] = min(out["min_margin_deg"], math.degrees(m))
        pair, low = check(q)
        if pair:
            out["pose_collisions"].append([k, pair])
        if low:
            out["below_table"].append([k, low])
    path = [q_of(p) for p in poses]
    if traj:
        path = trajectory_points(traj, rmodel, idx)
        stops = [path[i] for i in range(len(path) - 1)
                 if np.allclose(path[i], path[i + 1], atol=1e-9)]
        out["trajectory_points"] = len(path)
        out["stops_match_poses"] = len(stops) == len(poses) and all(
            np.allclose(a, q_of(p), atol=1e-6) for a, p in zip(stops, poses))
        out["via_points"] = sum(
            1 for q in path if not any(np.allclose(q, s, atol=1e-9) for s in stops))
    for k in range(len(path) - 1):
        a, b = path[k], path[k + 1]
        n = max(1, int(math.ceil(np.max(np.abs(b - a)) / step)))
        for s in range(1, n):
            q = a + (b - a) * (s / n)
            out["segment_points"] += 1
            pair, low = check(q)
            if pair or low:
                out["segment_collisions"].append([k, s / n, pair, low])
                break
    print(json.dumps(out))


if __name__ == "__main__":
    main()
