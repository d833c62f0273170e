#!/usr/bin/env bash
# Golden outputs: runs a fixed set of rigctl commands (the ones a refactoring of the
# identification must not change) and writes every stdout, JSON and model file they produce
# into one directory, so that two builds can be compared file by file:
#
#   bash scripts/golden.sh target/release/rigctl golden/before
#   ...change, rebuild...
#   bash scripts/golden.sh target/release/rigctl golden/after
#   diff -r golden/before golden/after
#
# Timings are not written (they differ run to run); everything else is deterministic (fixed
# seeds). Needs ../shared beside the checkout.
set -euo pipefail
cd "$(dirname "$0")/.."
rigctl=$(realpath "${1:?usage: golden.sh RIGCTL OUTDIR}")
out=${2:?usage: golden.sh RIGCTL OUTDIR}
rm -rf "$out"
mkdir -p "$out"
out=$(realpath "$out")
ur5=../shared/data/real/ur5_laser_tracker
tiago=../shared/data/real/thanhndv212__figaroh-examples/examples/tiago
train=$tiago/data/calibration/mocap/qualisys_2021-11-30_static_postures.csv
val=$tiago/data/calibration/mocap/qualisys_2021-11-26_static_postures.csv
ur5_tool=(--set tool_dx=0 --set tool_dy=0.07 --set tool_dz=31)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# run NAME CMD...: stdout to NAME.out, the exit code to NAME.rc (stderr dropped: progress bars)
run() {
  local name=$1
  shift
  set +e
  "$@" >"$out/$name.out" 2>/dev/null
  echo $? >"$out/$name.rc"
  set -e
}

"$rigctl" simulate --out "$work/k" --seed 7 --noise-mm 0.01 \
  --effect 'encoder_harmonic:j2:h1=0.03,40' >/dev/null 2>&1
run calibrate_katana "$rigctl" calibrate --poses "$work/k/cal.csv" --validate "$work/k/val.csv" \
  --json "$out/calibrate_katana.json" --out "$out/calibrate_katana.toml"
run calibrate_ur5_base "$rigctl" calibrate --robot ur5 "${ur5_tool[@]}" --base --method standard \
  --poses "$ur5/grid.csv" --validate "$ur5/random.csv" --json "$out/calibrate_ur5_base.json" \
  --out "$out/calibrate_ur5_base.toml"
"$rigctl" urdf2model --urdf "$tiago/urdf/tiago_48_schunk.urdf" --base-link base_footprint \
  --tip wrist_ft_tool_link --limit-margin-pct 1 --out "$work/tiago.toml" >/dev/null 2>&1
run calibrate_tiago_press "$rigctl" calibrate --model "$work/tiago.toml" --poses "$train" \
  --validate "$val" --units m,rad --markers 1 --method standard \
  --params @base,@tool,@offsets --select press --compliance --json "$out/calibrate_tiago_press.json"
run diagnose_katana "$rigctl" diagnose --poses "$work/k/cal.csv" --validate "$work/k/val.csv" \
  --instrument-mm 0.01 --json "$out/diagnose_katana.json" --out "$out/diagnose_katana.toml"
run diagnose_ur5 "$rigctl" diagnose --robot ur5 "${ur5_tool[@]}" --poses "$ur5/grid.csv" \
  --validate "$ur5/random.csv" --instrument-mm 0.015 --json "$out/diagnose_ur5.json"
for p in circle line; do
  s="$work/$p"
  "$rigctl" simulate --session $p --seed 7 --effect 'encoder_harmonic:j2:h1=0.03,40' \
    --out "$s" >/dev/null 2>&1
  "$rigctl" trace "$s/scan.png" --out "$s/trace.csv" >/dev/null 2>&1
  "$rigctl" potcal --points "$s/potjig.csv" --out "$s/pot.toml" >/dev/null 2>&1
  "$rigctl" fuse --joints "$s/joints.csv" --recording "$s/pot.rec" --trace "$s/trace.csv" \
    --placement "$s/placement.toml" --pot "$s/pot.toml" --out "$s/fused.csv" >/dev/null 2>&1
done
run diagnose_samples "$rigctl" diagnose --samples "$work/circle/fused.csv" \
  --validate "$work/line/fused.csv" --json "$out/diagnose_samples.json"
run plan "$rigctl" plan --tool-mm 330 --n 12 --seed 3 --out "$out/plan.csv" --json "$out/plan.json"
# transmission terms: the Katana model file with a term of every kind, used by fk and compensate
python3 - "$work/terms.toml" <<'PY'
import sys
text = open("host/models/katana450.toml").read()
blocks = text.split("[[joint]]")
terms = {2: "joint_scale = 0.0002\n", 3: "joint_coupling = { j2 = 0.002 }\n", 4: "hysteresis_deg = 0.03\n"}
for j, t in terms.items():
    blocks[j] = "\n" + t + blocks[j].lstrip("\n")
open(sys.argv[1], "w").write("[[joint]]".join(blocks))
PY
"$rigctl" simulate --out "$work/t" --seed 11 --noise-mm 0 >/dev/null 2>&1
run fk_transmission "$rigctl" fk --model "$work/terms.toml" --joints "$work/t/cal.csv"
# a reachable straight line, tool straight down, every 30 s
python3 - "$work/path.csv" <<'PY'
import sys
with open(sys.argv[1], "w") as f:
    f.write("t,x,y,z\n")
    for k in range(21):
        f.write(f"{k * 30},{300 + 5 * k},{-100 + 5 * k},150\n")
PY
run compensate_transmission "$rigctl" compensate --model "$work/terms.toml" --no-tilt \
  --path "$work/path.csv" --out "$out/compensate.csv"
mkdir -p "$work/r"
cp "$out/calibrate_katana.json" "$work/r/calibrate.json"
cp "$out/diagnose_katana.json" "$work/r/diagnose.json"
run report "$rigctl" report "$work/r" --html "$out/report.html"
# drop lines with timings or paths of the temporary directory
sed -i -E "s#$work#WORK#g; s#$out#OUT#g" "$out"/*.out "$out"/*.json "$out"/*.html 2>/dev/null || true
echo "golden outputs in $out"
