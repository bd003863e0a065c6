#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Seed corpora for the fuzz targets, from real encoded meshes.

usage: make_seeds.py OUT_DIR [PMZ_ENCODE]

Writes OUT_DIR/{decoder,container,coding}/. Tiny meshes (closed, open, with several
components) are generated here and encoded with pmz-encode at a few settings; the committed
tests/data/sample.pmz is always included. Without pmz-encode only that file seeds the corpus.
Seeds stay small (a few KB each) so that libFuzzer mutates them quickly.
"""
import math
import os
import struct
import subprocess
import sys
import tempfile

SIGNATURE = bytes([0x89, ord('P'), ord('M'), ord('Z'), 0x0D, 0x0A, 0x1A, 0x0A])


def varint(b, i):
    """LEB128 at b[i]: (value, index after it)."""
    v = shift = 0
    while True:
        x = b[i]
        i += 1
        v |= (x & 0x7F) << shift
        shift += 7
        if not x & 0x80:
            return v, i


def sphere(rings, segments, bump=0.0):
    v = [(0.0, 0.0, 1.0)]
    for i in range(1, rings):
        t = math.pi * i / rings
        for j in range(segments):
            p = 2 * math.pi * j / segments
            r = 1.0 + bump * math.sin(3 * p) * math.sin(2 * t)
            v.append((r * math.sin(t) * math.cos(p), r * math.sin(t) * math.sin(p), r * math.cos(t)))
    v.append((0.0, 0.0, -1.0))
    f = []
    for j in range(segments):
        f.append((0, 1 + j, 1 + (j + 1) % segments))
    for i in range(rings - 2):
        a, b = 1 + i * segments, 1 + (i + 1) * segments
        for j in range(segments):
            k = (j + 1) % segments
            f.append((a + j, b + j, b + k))
            f.append((a + j, b + k, a + k))
    last = len(v) - 1
    base = 1 + (rings - 2) * segments
    for j in range(segments):
        f.append((base + j, last, base + (j + 1) % segments))
    return v, f


def grid(n, height=0.2):
    v = [(x / n, y / n, height * math.sin(x) * math.cos(y)) for y in range(n + 1) for x in range(n + 1)]
    f = []
    for y in range(n):
        for x in range(n):
            a = y * (n + 1) + x
            f.append((a, a + 1, a + n + 2))
            f.append((a, a + n + 2, a + n + 1))
    return v, f


def merge(*meshes):
    v, f = [], []
    for mv, mf in meshes:
        o = len(v)
        v += mv
        f += [(a + o, b + o, c + o) for a, b, c in mf]
    return v, f


def write_off(path, mesh):
    v, f = mesh
    with open(path, 'w') as out:
        out.write('OFF\n%d %d 0\n' % (len(v), len(f)))
        for p in v:
            out.write('%.6f %.6f %.6f\n' % p)
        for t in f:
            out.write('3 %d %d %d\n' % t)


def main():
    out_dir = sys.argv[1]
    encoder = sys.argv[2] if len(sys.argv) > 2 else ''
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    files = {}
    sample = os.path.join(root, 'tests', 'data', 'sample.pmz')
    if os.path.exists(sample):
        files['sample'] = open(sample, 'rb').read()
    # Streams with attributes (format 8.0: HEAD attribute fields, ATTR chunks), committed.
    for name in ('seamed-coarse', 'seamed-lossless', 'terrain-nodes'):
        vector = os.path.join(root, 'tests', 'conformance', 'vectors', name + '.pmz')
        if os.path.exists(vector):
            files[name] = open(vector, 'rb').read()
    if encoder and os.access(encoder, os.X_OK):
        shifted = sphere(4, 6)
        shifted = ([(x + 3, y, z) for x, y, z in shifted[0]], shifted[1])
        meshes = {
            'octa': sphere(2, 4),
            'sphere': sphere(6, 8, 0.2),
            'grid': grid(5),
            'two': merge(sphere(3, 5), shifted),
            'nodes': sphere(24, 32, 0.2),
        }
        settings = {'q14': ['--position-bits', '14'], 'lossless': ['--position-bits', '0'],
                    'q4': ['--position-bits', '4'],
                    'speed': ['--level', '1'], 'speed-lossless': ['--level', '1', '--position-bits', '0'],
                    'cells': ['--cluster-vertices', '64']}
        with tempfile.TemporaryDirectory() as tmp:
            for name, mesh in meshes.items():
                off = os.path.join(tmp, name + '.off')
                write_off(off, mesh)
                for tag, args in settings.items():
                    pmz = os.path.join(tmp, '%s-%s.pmz' % (name, tag))
                    r = subprocess.run([encoder, off, '-o', pmz] + args, capture_output=True, text=True)
                    if r.returncode == 0 and os.path.exists(pmz):
                        files['%s-%s' % (name, tag)] = open(pmz, 'rb').read()
                    else:
                        print('make_seeds: %s %s: %s' % (name, tag, (r.stderr or r.stdout).strip()),
                              file=sys.stderr)
    # fuzz_region: [u32 cell][region]: the regions `pmz-encode --plan` writes for its tasks,
    # under the default metric and QEM (no face and vertex terms), and with attribute wedges and
    # materials (the conformance suite's seamed mesh).
    regions = {}
    if encoder and os.access(encoder, os.X_OK):
        with tempfile.TemporaryDirectory() as tmp:
            seamed = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'conformance',
                                  'meshes', 'seamed.obj')
            for name, mesh, args in (('sphere', sphere(12, 16, 0.2), ['--cluster-vertices', '16']),
                                     ('grid', grid(12), ['--cluster-vertices', '16']),
                                     ('grid-qem', grid(12), ['--cluster-vertices', '16',
                                                             '--metric', 'qem']),
                                     ('seamed', None, ['--cluster-vertices', '24'])):
                off = seamed
                if mesh is not None:
                    off = os.path.join(tmp, name + '.off')
                    write_off(off, mesh)
                plan = os.path.join(tmp, name + '-plan')
                r = subprocess.run([encoder, off, '--plan', plan, '-q'] + args,
                                   capture_output=True, text=True)
                if r.returncode != 0:
                    print('make_seeds: %s --plan: %s' % (name, r.stderr.strip()), file=sys.stderr)
                    continue
                for f in sorted(os.listdir(plan)):
                    if f.endswith('.region'):
                        cell = int(f[:-len('.region')])
                        data = open(os.path.join(plan, f), 'rb').read()
                        regions['%s-%d' % (name, cell)] = struct.pack('<I', cell) + data
    if not files:
        sys.exit('make_seeds: no seed: neither tests/data/sample.pmz nor a working pmz-encode')

    for sub in ('decoder', 'container', 'coding', 'view', 'region'):
        os.makedirs(os.path.join(out_dir, sub), exist_ok=True)

    def put(sub, name, data):
        with open(os.path.join(out_dir, sub, name), 'wb') as out:
            out.write(data)

    for name, data in regions.items():
        put('region', name, data)

    for name, data in files.items():
        put('container', name, data)
        # fuzz_view: [how][stream]: whole nodes, small budgets, wrong ranges, the rest in order.
        for how in (0, 0x21, 0x46, 0x8b):
            put('view', '%s-%02x' % (name, how), bytes([how]) + data)
        # fuzz_decoder: [n][n (slice, op) pairs][stream]. One call; byte-by-byte with refines;
        # mixed slices with coarsen/face-target/round-trip moves.
        put('decoder', name + '-whole', b'\x00' + data)
        put('decoder', name + '-bytes', bytes([1, 0, 1 << 2]) + data)
        put('decoder', name + '-mixed', bytes([4, 7, 5 << 2 | 1, 200, 9 << 2 | 2, 31, 3 << 2 | 3, 130, 2 << 2]) + data)
        # fuzz_coding: whole BASE payloads (part 7, after the counts HEAD gives them) and whole
        # SPLT payloads (part 6, with 256 vertices before, a generous split budget and a context
        # seed). Chunks: u8 type, varint size, u32 CRC, payload (spec/format.md section 3).
        at = 8
        counts = b''
        while at < len(data):
            kind = data[at]
            size, j = varint(data, at + 1)
            payload = data[j + 4:j + 4 + size]
            # HEAD: version (2 bytes), varint flags, 4 bytes (position bits, curvatures, level),
            # varint base counts, varint total splits (spec/format.md section 4)
            if kind == 1:
                node_minor = payload[1]
                node_flags, k = varint(payload, 2)
                k += 4
                _, e = varint(payload, k)
                _, e = varint(payload, e)
                counts = payload[k:e]
                node_total, _ = varint(payload, e)
            elif kind == 2:
                put('coding', '%s-BASE-%d' % (name, at), b'\x07' + counts + payload)
            elif kind == 3:
                put('coding', '%s-SPLT-%d' % (name, at), b'\x06\xff\xfb\x00' + payload)
            elif kind == 6:  # NODE: part 8, after HEAD's split total (u32) and flags byte
                # (bit 0 attributes, bit 1 cones: HEAD's minor version 1 or more)
                flags = (node_flags & 1) | (2 if node_minor >= 1 else 0)
                put('coding', '%s-NODE-%d' % (name, at),
                    b'\x08' + struct.pack('<I', node_total) + bytes([flags]) + payload)
            at = j + 4 + size
    # fuzz_coding, other parts: a few hand-made inputs.
    put('coding', 'reader', b'\x00\x10' + bytes(range(16)) + b'\x81\x80\x01\xff\xff\xff\xff\x0f' * 4)
    put('coding', 'varints', b'\x01' + struct.pack('<8Q', 0, 1, 127, 128, 1 << 35, 2**63, 2**64 - 1, 300))
    put('coding', 'quantizer', b'\x03\x0e' + struct.pack('<6f', -1, -2, -3, 1, 2, 3) + struct.pack('<4f', 0.5, -1, 3, 1e30))
    put('coding', 'range', b'\x05' + struct.pack('<8I', 0, 1, 2, 3, 1000, 65535, 2**31, 2**32 - 1))
    put('coding', 'mesh', b'\x04\x05\x04' + bytes([0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1, 0, 1, 0xff, 0xff, 0, 0]))
    total = sum(os.path.getsize(os.path.join(out_dir, s, f)) for s in ('decoder', 'container', 'coding')
                for f in os.listdir(os.path.join(out_dir, s)))
    print('make_seeds: %d encoded files, %d bytes of seeds in %s' % (len(files), total, out_dir))


if __name__ == '__main__':
    main()
