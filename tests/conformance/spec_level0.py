#!/usr/bin/env python3
"""A second decoder of the .pmz container, HEAD and BASE, written from spec/format.md alone
(sections 2 to 8 and 11), checked against the conformance vectors: for every .expected, the
stream status after feeding the whole file must be the expected one, and the level-0 mesh it
decodes must have the expected vertex and face counts and SHA-256. It decodes each SPLT chunk's group table but no split: the splits (section 9) are the
reference decoder's to check (ctest conformance_decode).

    python3 tests/conformance/spec_level0.py tests/conformance
"""
import hashlib
import math
import struct
import sys
import zlib
from pathlib import Path

SIGNATURE = bytes([0x89, 0x50, 0x4D, 0x5A, 0x0D, 0x0A, 0x1A, 0x0A])


class Refused(Exception):
    pass


def varint(b, at):  # section 2
    v = 0
    for i in range(10):
        if at + i >= len(b):
            raise Refused("corrupt")
        x = b[at + i]
        if i == 9 and x > 1:
            raise Refused("corrupt")
        v |= (x & 0x7F) << (7 * i)
        if not x & 0x80:
            return v, at + i + 1
    raise Refused("corrupt")


def unzigzag(y):
    return y // 2 if y % 2 == 0 else -(y + 1) // 2


def s32(x):  # modulo 2^32, signed
    x &= 0xFFFFFFFF
    return x - (1 << 32) if x >= 1 << 31 else x


class Model:  # section 11.1
    def __init__(self):
        self.p, self.cnt = 16384, 0

    def adapt(self, b):
        c = self.cnt
        shift = 2 if c < 8 else 3 if c < 16 else 4 if c < 48 else 5 if c < 127 else 6
        if b == 0:
            self.p += (32528 - self.p) >> shift
        else:
            self.p -= (self.p - 240) >> shift
        self.cnt = min(c + 1, 127)


class UIntModel:  # section 11.3
    def __init__(self):
        self.length = [Model() for _ in range(16)]
        self.escape = [Model() for _ in range(32)]
        self.high = [[Model() for _ in range(4)] for _ in range(33)]


class RangeDecoder:  # section 11.2
    def __init__(self, s):
        self.s, self.at, self.past = s, 0, False
        self.range = 0xFFFFFFFF
        self.code = 0
        for _ in range(4):
            self.code = (self.code << 8) | self.next()

    def next(self):
        if self.at < len(self.s):
            v = self.s[self.at]
        else:
            v = 0
            if self.at >= len(self.s) + 4:
                self.past = True
        self.at += 1
        return v

    def normalise(self):
        if self.range < 1 << 24:
            self.range = (self.range << 8) & 0xFFFFFFFF
            self.code = ((self.code << 8) | self.next()) & 0xFFFFFFFF

    def bit_p(self, p):
        bound = (self.range >> 15) * p
        if self.code < bound:
            self.range, b = bound, 0
        else:
            self.code -= bound
            self.range -= bound
            b = 1
        self.normalise()
        return b

    def bit(self, m):
        b = self.bit_p(m.p)
        m.adapt(b)
        return b

    def direct(self):
        self.range >>= 1
        if self.code >= self.range:
            self.code -= self.range
            b = 1
        else:
            b = 0
        self.normalise()
        return b

    def uint(self, m):
        node = 1
        for _ in range(4):
            node = 2 * node + self.bit(m.length[node])
        bl = node - 16
        if bl == 15:
            node = 1
            for _ in range(5):
                node = 2 * node + self.bit(m.escape[node])
            bl = 15 + node - 32
            if bl > 32:
                raise Refused("corrupt")
        if bl < 2:
            return bl
        x, node, rest = 1, 1, bl - 1
        for _ in range(min(2, rest)):
            b = self.bit(m.high[bl][node])
            node, x, rest = 2 * node + b, 2 * x + b, rest - 1
        for _ in range(rest):
            x = 2 * x + self.direct()
        return x


def read_head(p):  # section 4
    if len(p) < 2:
        raise Refused("corrupt")
    h = {"major": p[0], "minor": p[1]}
    at = 2
    h["flags"], at = varint(p, at)
    if at + 3 > len(p):
        raise Refused("corrupt")
    h["position_bits"], h["curvature"], h["fine_curvature"] = p[at], p[at + 1], p[at + 2]
    at += 3
    for name in ("base_vertices", "base_faces", "total_splits", "full_faces"):
        h[name], at = varint(p, at)
    if at + 24 > len(p):
        raise Refused("corrupt")
    h["bbox_min"] = struct.unpack_from("<3f", p, at)
    h["bbox_max"] = struct.unpack_from("<3f", p, at + 12)
    if any(h[n] >= 1 << 32 for n in ("flags", "base_vertices", "base_faces", "total_splits",
                                     "full_faces")):
        raise Refused("corrupt")
    if h["major"] != 7:
        raise Refused("bad_version")
    if h["flags"] != 0 or h["position_bits"] > 30 or h["curvature"] > 8 or h["fine_curvature"] > 8:
        raise Refused("corrupt")
    for a in range(3):
        lo, hi = h["bbox_min"][a], h["bbox_max"][a]
        if not (math.isfinite(lo) and math.isfinite(hi)) or hi < lo:
            raise Refused("corrupt")
    if h["base_faces"] > h["full_faces"] or h["full_faces"] > h["base_faces"] + 2 * h["total_splits"]:
        raise Refused("corrupt")
    if h["base_vertices"] + h["total_splits"] >= 1 << 32:
        raise Refused("corrupt")
    return h


def nxt(h):
    return h + 1 if h % 3 < 2 else h - 2


def prv(h):
    return h - 1 if h % 3 > 0 else h + 2


def decode_base(payload, nv, nf):  # section 7
    if nf > 384 * (len(payload) + 1) or nv > 64 * (len(payload) + 1):
        raise Refused("corrupt")
    rc = RangeDecoder(payload)
    face, is_right = Model(), Model()
    is_new = [Model() for _ in range(5)]
    is_left = [Model() for _ in range(2)]
    other = UIntModel()
    par = [UIntModel() for _ in range(3)]
    jump = [UIntModel() for _ in range(3)]
    F, c = [], []
    state = []  # per half-edge: "open", "glued", "boundary"
    out_l, in_l = {}, {}  # vertex -> list of open half-edges, most recent first
    gates, gate_at = [], 0

    def last():
        return c[-1] if c else (0, 0, 0)

    def new_vertex(pred, models):
        if len(c) >= nv:
            raise Refused("corrupt")
        c.append(tuple(s32(pred[a] + unzigzag(rc.uint(models[a]))) for a in range(3)))
        return len(c) - 1

    def vertex_symbol(fl, fr, context, pred, models):
        if rc.bit(is_new[context]) == 1:
            return new_vertex(pred, models)
        if fl is not None and rc.bit(is_left[1 if fr is not None else 0]) == 1:
            return fl
        if fr is not None and rc.bit(is_right) == 1:
            return fr
        back = rc.uint(other)
        if back >= len(c):
            raise Refused("corrupt")
        return len(c) - 1 - back

    def leave_open(h):
        out_l[F[h]].remove(h)
        in_l[F[nxt(h)]].remove(h)

    def add_face(x, y, z):
        h0 = len(F)
        F.extend((x, y, z))
        state.extend(("open", "open", "open"))
        for h in range(h0, h0 + 3):
            s, t = F[h], F[nxt(h)]
            g = next((e for e in out_l.get(t, []) if F[nxt(e)] == s), None)
            if g is not None:
                leave_open(g)
                state[g] = state[h] = "glued"
            else:
                out_l.setdefault(s, []).insert(0, h)
                in_l.setdefault(t, []).insert(0, h)
                gates.append(h)

    midpoint = rc.direct()
    while len(F) < 3 * nf:
        if rc.past:
            raise Refused("corrupt")
        h = None
        while gate_at < len(gates):
            g = gates[gate_at]
            gate_at += 1
            if state[g] == "open":
                h = g
                break
        if h is None:
            w = [vertex_symbol(None, None, 0, last(), jump) for _ in range(3)]
            if len(set(w)) != 3:
                raise Refused("corrupt")
            add_face(*w)
            continue
        ga, gb, gc = F[h], F[nxt(h)], F[prv(h)]
        if rc.bit(face) == 0:
            leave_open(h)
            state[h] = "boundary"
            continue
        fl = F[in_l[ga][0]] if in_l.get(ga) else None
        fr = F[nxt(out_l[gb][0])] if out_l.get(gb) else None
        if fr == fl:
            fr = None
        if midpoint == 0:
            pred = tuple(s32(c[ga][a] + c[gb][a] - c[gc][a]) for a in range(3))
        else:
            pred = tuple((c[ga][a] + c[gb][a]) >> 1 for a in range(3))
        w = vertex_symbol(fl, fr, 1 + (fl is not None) + 2 * (fr is not None), pred, par)
        if w in (ga, gb):
            raise Refused("corrupt")
        add_face(gb, ga, w)
    while len(c) < nv:
        new_vertex(last(), jump)
    if rc.past:
        raise Refused("corrupt")
    # Validity (section 6): no repeated directed edge, one fan per vertex.
    edges = {}
    for h in range(len(F)):
        e = (F[h], F[nxt(h)])
        if e in edges:
            raise Refused("corrupt")
        edges[e] = h
    corners = {}
    for h, x in enumerate(F):
        corners.setdefault(x, []).append(h)
    for x, hs in corners.items():
        seen, todo = {hs[0]}, [hs[0]]
        while todo:  # faces around x joined across their edges at x
            h = todo.pop()
            for e in ((x, F[nxt(h)]), (F[prv(h)], x)):
                o = edges.get((e[1], e[0]))
                if o is not None:
                    k = o if F[o] == x else nxt(o) if F[nxt(o)] == x else prv(o)
                    if k not in seen:
                        seen.add(k)
                        todo.append(k)
        if len(seen) != len(hs):
            raise Refused("corrupt")
    return c, F


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def positions(c, h):  # section 5
    out = []
    bits = h["position_bits"]
    if bits == 0:
        for x in c:
            for v in x:
                out.append(struct.pack("<i", v ^ 0x7FFFFFFF if v < 0 else v))
        return b"".join(out)
    size = max(f32(h["bbox_max"][a] - h["bbox_min"][a]) for a in range(3))
    scale = f32(size / f32(float((1 << bits) - 1))) if size > 0 else 0.0
    for x in c:
        for a in range(3):
            out.append(struct.pack("<f", f32(h["bbox_min"][a] + f32(f32(float(x[a])) * scale))))
    return b"".join(out)


def level0(data):
    """(stream status, HEAD, level-0 mesh) for the whole input (sections 3, 4, 7); HEAD and
    the mesh are None when not decoded. SPLT chunks are checked only for their split_count."""
    if data[:8] != SIGNATURE[: len(data[:8])]:
        return "bad_magic", None, None
    if len(data) < 8:
        return "truncated", None, None
    at, head, base, splits, done, first = 8, None, None, 0, False, True
    group_size, group_near = UIntModel(), Model()  # created once per stream (section 8)
    try:
        while at < len(data) and not done:
            if first and data[at : at + 4] == b"HEAD":
                raise Refused("bad_version")
            typ = data[at]
            size, p = varint(data, at + 1)
            if p + 4 + size > len(data):
                break  # incomplete: truncated
            crc = struct.unpack_from("<I", data, p)[0]
            payload = data[p + 4 : p + 4 + size]
            if zlib.crc32(data[at:p] + payload) != crc:
                raise Refused("bad_checksum")
            if first and typ != 1:
                raise Refused("corrupt")
            if typ == 1:
                if head is not None:
                    raise Refused("corrupt")
                head = read_head(payload)
            elif typ == 2:
                if base is not None:
                    raise Refused("corrupt")
                base = decode_base(payload, head["base_vertices"], head["base_faces"])
            elif typ == 3:
                if base is None:
                    raise Refused("corrupt")
                count, q = varint(payload, 0)
                if count == 0 or count > head["total_splits"] - splits:
                    raise Refused("corrupt")
                conn_size, q = varint(payload, q)
                if conn_size > len(payload) - q or count > 64 * len(payload):
                    raise Refused("corrupt")
                # The group table (section 8), with the stream's two group models.
                rc, total = RangeDecoder(payload[q : q + conn_size]), 0
                while total < count:
                    group = rc.uint(group_size) + 1
                    if group > count - total:
                        raise Refused("corrupt")
                    rc.bit(group_near)
                    total += group
                if rc.past:
                    raise Refused("corrupt")
                splits += count  # the splits themselves are not decoded here
            elif typ == 4:
                if base is None or splits != head["total_splits"]:
                    raise Refused("corrupt")
                done = True
            first = False
            at = p + 4 + size
    except Refused as e:
        return str(e), head, base
    return ("ok" if done else "truncated"), head, base


def main():
    root = Path(sys.argv[1])
    checked = failed = meshes = 0
    for exp in sorted(root.rglob("*.expected")):
        want = {}
        for line in exp.read_text().splitlines():
            w = line.split()
            if w and w[0] == "stream":
                want["stream"] = w[1]
            if w[:2] == ["level", "0"]:
                want["level0"] = (int(w[3]), int(w[5]), w[7])
        status, head, base = level0(exp.with_suffix(".pmz").read_bytes())
        got = {"stream": status}
        if base is not None:
            c, F = base
            blob = positions(c, head) + b"".join(struct.pack("<I", x) for x in F)
            got["level0"] = (len(c), len(F) // 3, hashlib.sha256(blob).hexdigest())
        # The stream status (everything but the splits: a stream refused at a split has status
        # ok after feeding) and the level-0 mesh wherever one is expected.
        ok = status == want["stream"]
        if "level0" in want:
            meshes += 1
            ok = ok and got.get("level0") == want["level0"]
        checked += 1
        if not ok:
            failed += 1
            print(f"FAIL {exp}: expected {want}, got {got}")
    print(f"{checked} files checked against spec sections 2-8 and 11 ({meshes} level-0 meshes), "
          f"{failed} failed")
    return 1 if failed or not checked else 0


if __name__ == "__main__":
    sys.exit(main())
