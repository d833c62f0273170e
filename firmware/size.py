#!/usr/bin/env python3
"""Prints the flash and static RAM use of the firmware ELF: "flash N bytes, ram N bytes".

Reads the ELF section headers with the standard library only (no binutils needed):
- flash: every allocated section with contents (SHT_PROGBITS etc., not SHT_NOBITS); this
  includes .data, whose initial values are stored in flash;
- ram: every allocated section placed in SRAM (0x2000_0000..0x4000_0000): .data, .bss,
  .uninit (the stack is not static and is not counted).
With --check, exits 1 when a budget is exceeded (flash 128 KiB, ram 48 KiB by default).
With --record NAME and the environment variable RIG_RESULTS_DIR set, also writes the sizes and
budgets as `NAME_flash_bytes`, `NAME_ram_bytes`, `flash_budget_bytes`, `ram_budget_bytes` into
`$RIG_RESULTS_DIR/firmware.json` (merged with what is there), the values `docs/results.md` is
rendered from (scripts/results.py).
"""

import argparse
import json
import os
import struct
import sys

SHF_ALLOC = 0x2
SHT_NOBITS = 8
RAM_START, RAM_END = 0x2000_0000, 0x4000_0000


def sections(data):
    if data[:4] != b"\x7fELF" or data[4] != 1 or data[5] != 1:
        raise ValueError("not a 32-bit little-endian ELF file")
    (shoff,) = struct.unpack_from("<I", data, 0x20)
    shentsize, shnum = struct.unpack_from("<HH", data, 0x2E)
    for i in range(shnum):
        off = shoff + i * shentsize
        _name, sh_type, flags, addr, _offset, size = struct.unpack_from("<IIIIII", data, off)
        yield sh_type, flags, addr, size


def measure(path):
    with open(path, "rb") as f:
        data = f.read()
    flash = ram = 0
    for sh_type, flags, addr, size in sections(data):
        if not flags & SHF_ALLOC or size == 0:
            continue
        if sh_type != SHT_NOBITS:
            flash += size
        if RAM_START <= addr < RAM_END:
            ram += size
    return flash, ram


def record(name, values):
    """Merges `values` into `$RIG_RESULTS_DIR/firmware.json`; nothing when the variable is unset."""
    folder = os.environ.get("RIG_RESULTS_DIR")
    if not folder:
        return
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, "firmware.json")
    doc = {}
    if os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    doc.update({f"{name}_{k}" if not k.endswith("budget_bytes") else k: v for k, v in values.items()})
    tmp = f"{path}.{os.getpid()}.tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(doc, f, indent=2, sort_keys=True)
        f.write("\n")
    os.replace(tmp, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("elf", nargs="?",
                        default="target/thumbv7em-none-eabihf/release/rig-firmware")
    parser.add_argument("--check", action="store_true", help="fail when over budget")
    parser.add_argument("--flash-budget", type=int, default=128 * 1024)
    parser.add_argument("--ram-budget", type=int, default=48 * 1024)
    parser.add_argument("--record", metavar="NAME",
                        help="write the sizes to $RIG_RESULTS_DIR/firmware.json as NAME_*")
    args = parser.parse_args()
    try:
        flash, ram = measure(args.elf)
    except (OSError, ValueError, struct.error) as e:
        print(f"size.py: {args.elf}: {e}", file=sys.stderr)
        return 2
    print(f"flash {flash} bytes, ram {ram} bytes")
    if args.record:
        record(args.record, {
            "flash_bytes": flash,
            "ram_bytes": ram,
            "flash_budget_bytes": args.flash_budget,
            "ram_budget_bytes": args.ram_budget,
        })
    if args.check and (flash > args.flash_budget or ram > args.ram_budget):
        print(f"over budget: flash <= {args.flash_budget}, ram <= {args.ram_budget}",
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
