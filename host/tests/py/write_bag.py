"""Writes rosbag2 (MCAP) joint logs with rosbags (pure Python, no ROS install): a consumer and
producer of ROS 2 bags that rigctl did not write.

usage:
  write_bag.py csv JOINTS.csv BAG_DIR --names N1,...,Nk [--prismatic 0,1,..] [--extra E1,E2]
               [--other-topic] [--shuffle] [--partial-every K]
      JOINTS.csv: t (s), q1..qk (deg, mm for prismatic joints). One sensor_msgs/msg/JointState
      per row on /joint_states, header stamp = 1700000000 s + t (exact, from the text of t),
      positions in rad (m). --extra adds joints the model does not have; --shuffle puts the
      names in another order in every message; --other-topic adds a std_msgs/msg/String topic
      and a second JointState topic; --partial-every K adds, after every K-th row, a message on
      /joint_states with only the extra joints (a gripper controller's); --zstd compresses the
      chunks (rosbag2's storage compression).
  write_bag.py synthetic BAG_DIR --count N --names N1,...,Nk [--extra E1,E2]
      N messages at 1 kHz, positions sin waves (rad), serialised once per message by hand as
      CDR and written with rosbags (fast enough for 10^6 messages).
"""
import argparse
import math
import struct
from decimal import Decimal

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode
from rosbags.typesys import Stores, get_typestore

BASE_NS = 1_700_000_000 * 10**9
TS = get_typestore(Stores.ROS2_HUMBLE)
JointState = TS.types["sensor_msgs/msg/JointState"]
Header = TS.types["std_msgs/msg/Header"]
Time = TS.types["builtin_interfaces/msg/Time"]
String = TS.types["std_msgs/msg/String"]


def joint_state(ns, names, pos):
    return JointState(
        header=Header(stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id="base"),
        name=list(names),
        position=np.array(pos, dtype=np.float64),
        velocity=np.zeros(len(pos), dtype=np.float64),
        effort=np.array([], dtype=np.float64),
    )


def from_csv(a):
    names = a.names.split(",")
    prismatic = [x == "1" for x in a.prismatic.split(",")] if a.prismatic else [False] * len(names)
    extra = a.extra.split(",") if a.extra else []
    with open(a.joints) as f:
        lines = [l.strip() for l in f if l.strip() and not l.startswith("#")]
    header = lines[0].split(",")
    ti = header.index("t")
    qi = [header.index(f"q{i + 1}") for i in range(len(names))]
    w = Writer(a.bag, version=8, storage_plugin=StoragePlugin.MCAP)
    if a.zstd:
        w.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    with w:
        js = w.add_connection("/joint_states", JointState.__msgtype__, typestore=TS)
        if a.other_topic:
            txt = w.add_connection("/rosout_text", String.__msgtype__, typestore=TS)
            cmd = w.add_connection("/joint_commands", JointState.__msgtype__, typestore=TS)
        for k, line in enumerate(lines[1:]):
            cells = line.split(",")
            ns = BASE_NS + int(Decimal(cells[ti]) * 10**9)
            pos = []
            for i, c in zip(prismatic, qi):
                v = float(cells[c])
                pos.append(v * 1e-3 if i else math.radians(v))
            all_names = names + extra
            all_pos = pos + [0.25 * (j + 1) for j in range(len(extra))]
            order = list(range(len(all_names)))
            if a.shuffle:
                r = k % len(order)
                order = order[r:] + order[:r]
                if k % 2:
                    order.reverse()
            msg = joint_state(ns, [all_names[i] for i in order], [all_pos[i] for i in order])
            w.write(js, ns, TS.serialize_cdr(msg, JointState.__msgtype__))
            if a.other_topic:
                w.write(txt, ns, TS.serialize_cdr(String(data=f"row {k}"), String.__msgtype__))
                bogus = joint_state(ns, names, [9.0] * len(names))
                w.write(cmd, ns, TS.serialize_cdr(bogus, JointState.__msgtype__))
            if a.partial_every and extra and k % a.partial_every == 0:
                part = joint_state(ns + 1, extra, [0.5] * len(extra))
                w.write(js, ns + 1, TS.serialize_cdr(part, JointState.__msgtype__))


def cdr_string(out, s):
    b = s.encode() + b"\0"
    while (len(out) - 4) % 4:
        out.append(0)
    out += struct.pack("<I", len(b)) + b


def synthetic(a):
    names = a.names.split(",") + (a.extra.split(",") if a.extra else [])
    with Writer(a.bag, version=8, storage_plugin=StoragePlugin.MCAP) as w:
        js = w.add_connection("/joint_states", JointState.__msgtype__, typestore=TS)
        head = bytearray()
        for n in names:
            cdr_string(head, n)
        for k in range(a.count):
            ns = BASE_NS + k * 1_000_000
            out = bytearray(b"\x00\x01\x00\x00")
            out += struct.pack("<iI", ns // 10**9, ns % 10**9)
            cdr_string(out, "base")
            while (len(out) - 4) % 4:
                out.append(0)
            out += struct.pack("<I", len(names))
            # names: re-align the precomputed block (it was built from offset 0 mod 4)
            out += head
            while (len(out) - 4) % 4:
                out.append(0)
            out += struct.pack("<I", len(names))
            while (len(out) - 4) % 8:
                out.append(0)
            out += struct.pack(f"<{len(names)}d", *[0.5 * math.sin(1e-3 * k + j) for j in range(len(names))])
            out += struct.pack("<II", 0, 0)
            w.write(js, ns, bytes(out))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("mode", choices=["csv", "synthetic"])
    p.add_argument("args", nargs="+")
    p.add_argument("--names", required=True)
    p.add_argument("--prismatic")
    p.add_argument("--extra")
    p.add_argument("--other-topic", action="store_true")
    p.add_argument("--shuffle", action="store_true")
    p.add_argument("--partial-every", type=int, default=0)
    p.add_argument("--count", type=int, default=0)
    p.add_argument("--zstd", action="store_true")
    a = p.parse_args()
    if a.mode == "csv":
        a.joints, a.bag = a.args
        from_csv(a)
    else:
        (a.bag,) = a.args
        synthetic(a)


if __name__ == "__main__":
    main()
