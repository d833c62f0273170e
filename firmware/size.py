#!/usr/bin/env python3
"""Prints the flash and static RAM use of the firmware ELF: "flash N bytes, ram N bytes".

Reads the ELF section headers with the standard library only (no binutils needed):
- flash: every allocated section with contents (SHT_PROGBITS etc., not SHT_NOBITS); this
  includes .data, whose initial values are stored in flash;
- ram: every allocated section placed in SRAM (0x2000_0000..0x4000_0000): .data, .bss,
  .uninit (the stack is not static and is not counted).
With --check, exits 1 when a budget is exceeded (flash 128 KiB, ram 48 KiB by default).
"""

import argparse
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


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("elf", nargs="?",
                        default="target/thumbv7em-none-eabihf/release/rig-firmware")
    parser.add_argument("--check", action="store_true", help="fail when over budget")
    parser.add_argument("--flash-budget", type=int, default=128 * 1024)
    parser.add_argument("--ram-budget", type=int, default=48 * 1024)
    args = parser.parse_args()
    try:
        flash, ram = measure(args.elf)
    except (OSError, ValueError, struct.error) as e:
        print(f"size.py: {args.elf}: {e}", file=sys.stderr)
        return 2
    print(f"flash {flash} bytes, ram {ram} bytes")
    if args.check and (flash > args.flash_budget or ram > args.ram_budget):
        print(f"over budget: flash <= {args.flash_budget}, ram <= {args.ram_budget}",
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
