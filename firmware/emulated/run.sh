#!/usr/bin/env bash
# Runs the firmware on the emulated board (QEMU mps2-an386, a Cortex-M4F).
#
#   bash firmware/emulated/run.sh DURATION_S LINK [SWITCH...]
#
# Builds the `mps2-an386` firmware if needed (firmware/target/mps2/), starts QEMU with the
# board's UART0 on a pseudo-terminal, links it at LINK (like `rigctl board-sim --link`) and
# ends QEMU after DURATION_S seconds (exit 0). The firmware's log, panics and hard faults come
# over semihosting on stdout; a panic or fault ends QEMU early and this script exits 1. A lockup
# (a fault while entering the fault handler: a stack overflow off the bottom of RAM) ends QEMU
# too: this script says so on stdout ("FAULT stack overflow" when the stack pointer is below
# RAM) and exits 1.
# SWITCH: panic-after-ms=N (panic N ms after boot, to see that it is reported);
#         overflow-after-ms=N (recurse without end N ms after boot: a stack overflow).
set -euo pipefail

usage() { echo "usage: run.sh DURATION_S LINK [panic-after-ms=N] [overflow-after-ms=N]" >&2; exit 2; }
[ $# -ge 2 ] || usage
duration=$1
link=$2
shift 2
[[ $duration =~ ^[0-9]+$ ]] && [ "$duration" -gt 0 ] || usage
for switch in "$@"; do
  [[ $switch =~ ^(panic|overflow)-after-ms=[0-9]+$ ]] || usage
done

here=$(cd "$(dirname "$0")" && pwd)
firmware=$(dirname "$here")
if ! command -v qemu-system-arm >/dev/null 2>&1; then
  echo "run.sh: qemu-system-arm not found (Debian: apt-get install qemu-system-arm)" >&2
  exit 3
fi
if ! command -v flip-link >/dev/null 2>&1; then
  echo "run.sh: flip-link not found, the firmware's linker (cargo install flip-link --locked)" >&2
  exit 3
fi
(cd "$firmware" && cargo build --release --locked --quiet \
  --no-default-features --features mps2-an386 --target-dir target/mps2)
elf=$firmware/target/mps2/thumbv7em-none-eabihf/release/rig-firmware

# RAM of the emulated board (firmware/build.rs, MPS2_MEMORY_X): the stack's floor.
ram_start=$((0x20000000))

semihosting="enable=on,target=native,arg=rig-firmware"
for switch in "$@"; do semihosting+=",arg=$switch"; done

qemu_log=$(mktemp)
qemu_pid=
console_pid=
cleanup() {
  if [ -n "$qemu_pid" ] && kill -0 "$qemu_pid" 2>/dev/null; then
    kill "$qemu_pid" 2>/dev/null || true
    wait "$qemu_pid" 2>/dev/null || true
  fi
  [ -L "$link" ] && rm -f "$link"
  sleep 0.3 # let tail print QEMU's last lines
  rm -f "$qemu_log"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# QEMU's clock follows the host's (no -icount): board time is real time, which is what the
# host's rates and timeouts expect. The board idles in WFI (QEMU uses about 7 % of a core at
# 1 kHz + 3 x 100 Hz) but must wake within a tilt slot (3.3 ms at 3 x 100 Hz) or the slot is
# skipped (and counted as an overrun). On a busy host that needs a real-time priority: QEMU
# runs as SCHED_FIFO 1 when allowed (the kernel's RT throttling still leaves the host 5 % of a
# core should the guest ever spin), else at nice -10, else as it is.
if chrt -f 1 true 2>/dev/null; then
  priority=(chrt -f 1)
elif nice -n -10 true 2>/dev/null; then
  priority=(nice -n -10)
else
  priority=()
fi
ulimit -c 0 # QEMU aborts on a lockup: no core file
"${priority[@]}" qemu-system-arm -machine mps2-an386 -display none -monitor none \
  -chardev pty,id=link -serial chardev:link \
  -semihosting-config "$semihosting" \
  -kernel "$elf" >"$qemu_log" 2>&1 &
qemu_pid=$!

pts=
for _ in $(seq 1 100); do
  pts=$(grep -o '/dev/pts/[0-9]*' "$qemu_log" | head -n 1 || true)
  [ -n "$pts" ] && break
  kill -0 "$qemu_pid" 2>/dev/null || break
  sleep 0.05
done
if [ -z "$pts" ]; then
  cat "$qemu_log" >&2
  echo "run.sh: QEMU did not open a pseudo-terminal" >&2
  exit 1
fi
ln -sfn "$pts" "$link"
echo "run.sh: board UART0 on $pts, linked at $link, for ${duration} s" >&2
# QEMU's output (the firmware's semihosting console) goes on to this script's stdout.
tail -n +1 -f --pid="$qemu_pid" "$qemu_log" | grep --line-buffered -v 'char device redirected' &
console_pid=$!

end=$((SECONDS + duration))
while kill -0 "$qemu_pid" 2>/dev/null && [ "$SECONDS" -lt "$end" ]; do
  sleep 0.1
done
if kill -0 "$qemu_pid" 2>/dev/null; then
  echo "run.sh: ${duration} s elapsed, stopping QEMU" >&2
  exit 0
fi
status=0
wait "$qemu_pid" || status=$?
qemu_pid=
wait "$console_pid" 2>/dev/null || true # the console's last lines first
echo "run.sh: QEMU exited early with status $status" >&2
# A fault the core cannot take (a fault while entering HardFault: its exception frame cannot
# be stacked) is a lockup; QEMU does not model lockup and aborts with "Lockup: can't escalate
# ..." and the registers. The usual cause is a stack overflow: flip-link puts the stack at the
# bottom of RAM, so an overflow leaves the stack pointer (R13) below RAM, where the HardFault
# handler cannot run either. Reported here, on the console (stdout), where the firmware's own
# panics and faults go.
if grep -q 'Lockup:' "$qemu_log"; then
  lockup=$(grep -m 1 -o 'Lockup:.*' "$qemu_log")
  sp=$(grep -m 1 -o 'R13=[0-9a-fA-F]*' "$qemu_log" | cut -d= -f2 || true)
  if [ -n "$sp" ] && (( 16#$sp < ram_start )); then
    printf 'run.sh: FAULT stack overflow: the board locked up (%s) with its stack pointer at 0x%s, below the start of RAM 0x%08x\n' \
      "$lockup" "$sp" "$ram_start"
  else
    printf 'run.sh: FAULT the board locked up (%s), stack pointer 0x%s\n' "$lockup" "${sp:-unknown}"
  fi
  exit 1
fi
exit $(( status == 0 ? 1 : status ))
