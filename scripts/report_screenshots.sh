#!/usr/bin/env bash
# The report's first screen in headless Chromium (1280 x 800) for three runs, written to
# docs/screenshots/: a simulated Katana 450 with an undeclared encoder harmonic, the UR5 with a
# laser tracker (../shared/data/real/ur5_laser_tracker) and an own robot from its URDF (TIAGo,
# FIGAROH's motion-capture postures, the model from `urdf2model`).
#
#   bash scripts/report_screenshots.sh [RIGCTL] [WORKDIR]
#
# RIGCTL defaults to target/release/rigctl (built when missing), WORKDIR to a temporary
# directory (kept, its path printed). Needs /usr/bin/chromium.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cd "$ROOT"
R=${1:-target/release/rigctl}
[ -x "$R" ] || cargo build --release -p rigctl
R=$(realpath "$R")
W=${2:-$(mktemp -d)}
mkdir -p "$W"
W=$(realpath "$W")
OUT=$ROOT/docs/screenshots
CHROMIUM=${CHROMIUM:-/usr/bin/chromium}

# 1. Katana 450, simulated (the five-minute tour of the README)
K=$W/katana
"$R" simulate --out "$K" --seed 7 --effect 'encoder_harmonic:j2:h1=0.03,40' >/dev/null
"$R" calibrate --poses "$K/cal.csv" --validate "$K/val.csv" --json "$K/calibrate.json" \
    --out "$K/calibrated.toml" >/dev/null
"$R" diagnose --poses "$K/cal.csv" --validate "$K/val.csv" --json "$K/diagnose.json" \
    --out "$K/extended.toml" >/dev/null || [ $? -eq 1 ]
"$R" report "$K" --html "$K/report.html" >/dev/null

# 2. UR5 with a laser tracker (README "Your own robot", worked example)
D=$ROOT/../shared/data/real/ur5_laser_tracker
U=$W/ur5
mkdir -p "$U"
UR5=(--robot ur5 --set tool_dx=0 --set tool_dy=0.07 --set tool_dz=31)
"$R" calibrate "${UR5[@]}" --base --method standard --poses "$D/grid.csv" \
    --validate "$D/random.csv" --json "$U/calibrate.json" --out "$U/calibrated.toml" >/dev/null
"$R" diagnose "${UR5[@]}" --poses "$D/grid.csv" --validate "$D/random.csv" \
    --instrument-mm 0.015 --json "$U/diagnose.json" --out "$U/extended.toml" >/dev/null \
    || [ $? -eq 1 ]
"$R" report "$U" --html "$U/report.html" --robot ur5 >/dev/null

# 3. An own robot from its URDF: TIAGo with motion capture (docs/calibrate.md, TIAGo)
T=$ROOT/../shared/data/real/thanhndv212__figaroh-examples/examples/tiago
TRAIN=$T/data/calibration/mocap/qualisys_2021-11-30_static_postures.csv
VAL=$T/data/calibration/mocap/qualisys_2021-11-26_static_postures.csv
G=$W/tiago
mkdir -p "$G"
"$R" urdf2model --urdf "$T/urdf/tiago_48_schunk.urdf" --base-link base_footprint \
    --tip wrist_ft_tool_link --limit-margin-pct 1 --out "$G/tiago.toml" >/dev/null
"$R" calibrate --model "$G/tiago.toml" --poses "$TRAIN" --validate "$VAL" --units m,rad \
    --markers 1 --method standard --params @base,@tool,@offsets --select press --compliance \
    --json "$G/calibrate.json" --out "$G/calibrated.toml" >/dev/null || [ $? -eq 1 ]
"$R" diagnose --model "$G/tiago.toml" --poses "$TRAIN" --validate "$VAL" --units m,rad \
    --marker 1 --instrument-mm 0.3 --json "$G/diagnose.json" --out "$G/extended.toml" \
    >/dev/null || [ $? -eq 1 ]
"$R" report "$G" --html "$G/report.html" >/dev/null

shot() {
    local page=$1 png=$2 profile
    profile=$(mktemp -d)
    "$CHROMIUM" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
        --disable-background-networking --disable-component-update --disable-sync \
        --user-data-dir="$profile" --hide-scrollbars --screenshot="$png" \
        --window-size=1280,800 "file://$page" >/dev/null 2>&1
    rm -rf "$profile"
    echo "$png"
}
shot "$K/report.html" "$OUT/first_screen_katana.png"
shot "$U/report.html" "$OUT/first_screen_ur5.png"
shot "$G/report.html" "$OUT/first_screen_own_robot.png"
echo "runs in $W"
