#!/usr/bin/env bash
# The main job on the built-in virtual rig, from a fresh machine:
#   1. set up: the Rust target for the board, a release build of rigctl;
#   2. simulate a Katana 450 with random geometric errors + joint tilting (known truth);
#   3. calibrate it (standard vs tilting-first) on 118 ISO-9283 poses, validate on held-out poses;
#   4. diagnose: look for effects the declared model lacks (here: an undeclared encoder harmonic);
#   5. the low-cost rig on the same robot: a simulated session per sheet (circle, line: joint log,
#      board recording, 600 dpi scan), trace -> pot calibration -> fusion -> calibrate --samples
#      (thesis fig. 5.12 path error) -> diagnose --samples (circle), held out on the line;
#   6. an HTML report with the plots.
# Results go to runs/demo/ (or the folder given as $1).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-runs/demo}

rustup target add thumbv7em-none-eabihf >/dev/null 2>&1 || echo "note: could not add the board target (only needed for firmware/)"
cargo build --release -p rigctl --locked
rigctl=target/release/rigctl
mkdir -p "$out"

echo "== simulate: virtual Katana 450 with an undeclared encoder harmonic on joint 2"
"$rigctl" simulate --out "$out" --seed 7 --noise-mm 0.01 --effect 'encoder_harmonic:j2:h1=0.03,40'

echo "== calibrate --method standard (no tilting)"
"$rigctl" calibrate --poses "$out/cal.csv" --validate "$out/val.csv" --method standard \
  --json "$out/calibrate_standard.json"

echo "== calibrate (tilting first, the default)"
"$rigctl" calibrate --poses "$out/cal.csv" --validate "$out/val.csv" \
  --json "$out/calibrate.json" --out "$out/calibrated.toml"

echo "== diagnose: what does the declared model lack?"
"$rigctl" diagnose --poses "$out/cal.csv" --validate "$out/val.csv" \
  --json "$out/diagnose.json" --out "$out/extended.toml" --plots "$out/plots"

echo "== the low-cost rig: pencil sessions drawn by the same robot (truth: encoder harmonic on joint 2)"
for path in circle line; do
  s="$out/session_$path"
  "$rigctl" simulate --session "$path" --seed 7 --effect 'encoder_harmonic:j2:h1=0.03,40' --out "$s"
  "$rigctl" trace "$s/scan.png" --out "$s/trace.csv"
  "$rigctl" potcal --points "$s/potjig.csv" --out "$s/pot.toml"
  "$rigctl" fuse --joints "$s/joints.csv" --recording "$s/pot.rec" --trace "$s/trace.csv" \
    --placement "$s/placement.toml" --pot "$s/pot.toml" --out "$s/fused.csv"
done
echo "== calibrate --samples (circle): measured path error before / standard / tilting"
"$rigctl" calibrate --samples "$out/session_circle/fused.csv" \
  --errors-csv "$out/path_errors.csv" --plot "$out/path_errors.svg" --json "$out/calibrate_samples.json"
echo "== diagnose --samples (circle), held out on the line"
"$rigctl" diagnose --samples "$out/session_circle/fused.csv" --validate "$out/session_line/fused.csv" \
  --json "$out/diagnose_samples.json"

echo "== report"
"$rigctl" report "$out" --html "$out/report.html"
echo "results in $out/ (open $out/report.html)"
