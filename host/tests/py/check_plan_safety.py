#!/usr/bin/env python3
"""Independent safety check of a `rigctl plan` output with pinocchio + coal (hpp-fcl).

    check_plan_safety.py URDF SRDF PACKAGE_DIR PLAN.csv JOINT,NAMES TABLE_Z_MM STEP_DEG

Loads the URDF with its collision meshes (the meshes themselves, as BVH models), locks every
joint that is not in JOINT,NAMES at its neutral value, checks every pair of geometries of
different joints except the SRDF's disabled pairs, and a half-space below z = TABLE_Z_MM (m
in pinocchio) against every geometry not fixed to the base. Checks each planned pose (the
plan's order) and the straight joint-space segments between consecutive poses at STEP_DEG,
every frame origin above the table, and the joint margins. Prints one JSON object.
"""
import csv
import json
import math
import sys

import numpy as np
import pinocchio as pin
import coal


def main():
    urdf, srdf, pkg, plan_csv, names, table_z_mm, step_deg = sys.argv[1:8]
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
    for k in range(len(poses) - 1):
        a, b = q_of(poses[k]), q_of(poses[k + 1])
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
