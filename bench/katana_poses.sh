#!/usr/bin/env bash
# Large Katana pose file for the `calibrate --poses` speed bar (README Benchmarks):
#   bench/katana_poses.sh N OUT.csv [RIGCTL]
# Random joints in the table 3.1 limits (fixed seed), positions from `rigctl fk --tilt` with
# four geometric errors set, plus uniform +-0.01 mm noise. Needs python3 (standard library).
set -euo pipefail
n=${1:?N}; out=${2:?OUT.csv}; rigctl=${3:-target/release/rigctl}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
python3 - "$n" > "$tmp/q.csv" <<'PY'
import random, sys
random.seed(200000)
lim = [(-169.5, 169.5), (-30, 102), (-122.5, 122.5), (-112, 112), (-168, 168)]
print("q1,q2,q3,q4,q5")
for _ in range(int(sys.argv[1])):
    print(",".join("%.9f" % random.uniform(a, b) for a, b in lim))
PY
"$rigctl" fk --tilt --joints "$tmp/q.csv" --set dth2=0.03 --set al3=0.02 --set dth4=-0.05 --set be3=0.01 > "$tmp/fk.csv"
python3 - "$tmp/q.csv" "$tmp/fk.csv" > "$out" <<'PY'
import random, sys
random.seed(7)
q = open(sys.argv[1]).read().split("\n")
fk = [l for l in open(sys.argv[2]).read().split("\n") if l and not l.startswith(("x", "#"))]
print("q1,q2,q3,q4,q5,x,y,z")
for qi, f in zip(q[1:], fk):
    x, y, z = (float(v) + random.uniform(-0.01, 0.01) for v in f.split(",")[:3])
    print("%s,%.6f,%.6f,%.6f" % (qi, x, y, z))
PY
