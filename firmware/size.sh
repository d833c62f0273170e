#!/usr/bin/env bash
# Builds nothing: prints "flash N bytes, ram N bytes" for the release ELF (build it first with
# `cargo build --release`). Extra arguments go to size.py (e.g. --check to enforce the budget
# of 128 KiB flash / 48 KiB static RAM). Needs only python3.
set -euo pipefail
cd "$(dirname "$0")"
exec python3 size.py "$@"
