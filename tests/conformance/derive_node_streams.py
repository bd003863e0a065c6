#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Derives edge-case streams from a valid stream in nodes (spec/format.md section 15) by
editing its NODE chunk, its normal cones (15.5) or its chunk order: OUT_DIR/node-*.pmz, each
printed as its name and what it is ("valid: ..." or "invalid: ..."). regenerate.sh runs it on
vectors/seamed-nodes.pmz and has the reference decoder write each one's .expected.

    python3 tests/conformance/derive_node_streams.py NODES.pmz OUT_DIR
"""
import copy
import struct
import sys
import zlib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import spec_decoder as sd  # noqa: E402


def put_varint(v):
    out = bytearray()
    while True:
        low, v = v & 0x7F, v >> 7
        out.append(low | (0x80 if v else 0))
        if not v:
            return bytes(out)


def put_zvarint(v):
    return put_varint(-2 * v - 1 if v < 0 else 2 * v)


def chunk(typ, payload):
    head = bytes([typ]) + put_varint(len(payload))
    return head + struct.pack("<I", zlib.crc32(head + payload)) + payload


def chunks(data):
    at, out = 8, []
    while at < len(data):
        typ = data[at]
        size, p = sd.varint(data, at + 1)
        out.append((typ, data[p + 4 : p + 4 + size]))
        at = p + 4 + size
        if typ == 4:
            return out
    return out


def fields(attributes):  # a node's varints after its cell (spec/format.md section 15.1)
    return ("splits", "faces", "wedges", "bytes") if attributes else ("splits", "faces", "bytes")


def read_table(p, attributes, cones):  # the fields of spec/format.md section 15.1, floats as bytes
    count, at = sd.varint(p, 0)
    levels, nodes = [], []
    for _ in range(count):
        side, at = sd.varint(p, at)
        origin = []
        for _ in range(3):
            o, at = sd.zvarint(p, at)
            origin.append(o)
        levels.append((side, origin))
    count, at = sd.varint(p, at)
    for _ in range(count):
        n = {"cell": []}
        n["level"], at = sd.varint(p, at)
        for _ in range(3 if levels[n["level"]][0] else 0):
            x, at = sd.zvarint(p, at)
            n["cell"].append(x)
        for name in fields(attributes):
            n[name], at = sd.varint(p, at)
        n["floats"], at = p[at : at + 20], at + 20
        nodes.append(n)
    for n in nodes:  # (version_minor >= 1: four bytes of normal cone per node, 15.5)
        n["cone"], at = (p[at : at + 4], at + 4) if cones else (b"", at)
    return levels, nodes


def write_table(levels, nodes, attributes):
    out = put_varint(len(levels))
    for side, origin in levels:
        out += put_varint(side) + b"".join(put_zvarint(o) for o in origin)
    out += put_varint(len(nodes))
    for n in nodes:
        out += put_varint(n["level"]) + b"".join(put_zvarint(x) for x in n["cell"])
        out += b"".join(put_varint(n[name]) for name in fields(attributes))
        out += n["floats"]
    return out + b"".join(n["cone"] for n in nodes)


def main():
    src, out = Path(sys.argv[1]), Path(sys.argv[2])
    data = src.read_bytes()
    cs = chunks(data)
    at = next(i for i, (typ, _) in enumerate(cs) if typ == 6)
    attributes = bool(cs[0][1][2] & 1)  # HEAD flags (a one-byte varint)
    minor = cs[0][1][1]
    levels, nodes = read_table(cs[at][1], attributes, minor >= 1)
    made = {}

    def table(edit):
        n = copy.deepcopy(nodes)
        edit(n)
        return cs[:at] + [(6, write_table(levels, n, attributes))] + cs[at + 1 :]

    made["node-missing"] = cs[:at] + cs[at + 1 :], \
        "invalid: no NODE chunk although HEAD flag bit 1"
    made["node-twice"] = cs[: at + 2] + [cs[at]] + cs[at + 2 :], "invalid: a second NODE chunk"
    made["node-late"] = cs[:at] + [cs[at + 1], cs[at]] + cs[at + 2 :], \
        "invalid: NODE after a chunk of node 1"
    made["node-bytes-long"] = table(lambda n: n[1].update(bytes=n[1]["bytes"] + 1)), \
        "invalid: node 1's bytes one more than its chunks"
    made["node-bytes-short"] = table(lambda n: n[1].update(bytes=n[1]["bytes"] - 1)), \
        "invalid: node 1's bytes one less than its chunks"
    made["node-faces-first"] = table(lambda n: n[0].update(faces=n[0]["faces"] - 1)), \
        "invalid: node 0's faces one less than its splits add"
    made["node-faces"] = table(lambda n: n[2].update(faces=n[2]["faces"] - 1)), \
        "invalid: node 2's faces one less than its splits add"
    made["node-faces-last"] = table(lambda n: n[-1].update(faces=n[-1]["faces"] - 1)), \
        "invalid: the last node's faces one less than its splits add"
    made["node-cell-moved"] = table(
        lambda n: n[3]["cell"].__setitem__(0, n[3]["cell"][0] + 1)), "invalid: node 3's cell moved"
    made["node-child-first"] = table(lambda n: n.insert(1, n.pop())), \
        "invalid: the last node moved before its parents"
    # Flag bit 1 cleared: the NODE chunk is of unknown type and the later nodes' chunks decode
    # as one stream (their groups, coded for models of their own, then span several chunks).
    head = bytearray(cs[0][1])
    head[2] &= 0xFD
    made["node-flag-cleared"] = [(1, bytes(head))] + cs[1:], \
        "invalid: HEAD flag bit 1 cleared: NODE is an unknown chunk"
    made["node-truncated"] = cs[: at + 3], "invalid: cut after node 2's first chunk"
    # Normal cones (15.5): a block cut short is refused; any values are hints, never refused;
    # with minor version 0 the block is bytes after the last node's error, ignored.
    made["node-cones-short"] = cs[:at] + [(6, cs[at][1][:-1])] + cs[at + 1 :], \
        "invalid: the NODE payload cut one byte short of the last node's cone"
    wild = [bytes([0, 0, 0, 9]), bytes([0x80, 0x7F, 3, 127]), bytes([1, 2, 3, 128]),
            bytes([0x81, 0, 0, 0])]
    made["node-cones-any"] = table(
        lambda n: [m.update(cone=wild[k % 4]) for k, m in enumerate(n)]), \
        "valid: every cone replaced (a zero axis, cutoffs 0, 127 and above), not refused"
    head = bytearray(cs[0][1])
    head[1] = 0
    made["node-minor-zero"] = [(1, bytes(head))] + cs[1:], \
        "valid: HEAD's minor version 0: the cones are bytes after the table, ignored"
    out.mkdir(parents=True, exist_ok=True)
    for name, (parts, what) in made.items():
        end = [chunk(typ, p) for typ, p in parts]
        (out / f"{name}.pmz").write_bytes(data[:8] + b"".join(end))
        print(name, what)
    return 0


if __name__ == "__main__":
    sys.exit(main())
