#!/usr/bin/env bash
# Builds nothing: prints "flash N bytes, ram N bytes" for the release ELF of the STM32 build
# (`cargo build --release`) and, when it has been built, of the emulated MPS2 AN386 build
# (`emulated/run.sh` or `cargo build --release --no-default-features --features mps2-an386
# --target-dir target/mps2`). Extra arguments go to size.py (e.g. --check to enforce the
# budget of 128 KiB flash / 48 KiB static RAM on each). With RIG_RESULTS_DIR set, the sizes are
# also written to $RIG_RESULTS_DIR/firmware.json (`stm32_*`, `mps2_*`; docs/results.md's
# Firmware rows). Needs only python3.
set -euo pipefail
cd "$(dirname "$0")"
stm32=target/thumbv7em-none-eabihf/release/rig-firmware
mps2=target/mps2/thumbv7em-none-eabihf/release/rig-firmware
printf 'stm32 (%s): ' "$stm32"
python3 size.py "$stm32" --record stm32 "$@"
if [ -f "$mps2" ]; then
  printf 'mps2-an386 (%s): ' "$mps2"
  python3 size.py "$mps2" --record mps2 "$@"
fi
