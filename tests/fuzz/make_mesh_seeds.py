#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Seed corpora for the mesh reader fuzz targets (fuzz_mesh_obj, _off, _ply, _stl, _gltf) and
the repair pass's (fuzz_mesh_repair).

usage: make_mesh_seeds.py OUT_DIR

Writes OUT_DIR/mesh_{obj,off,ply,stl,gltf}/: a small cube with a texture seam, normals, colours
and two materials in every layout each reader knows (ascii and binary, polygons, glTF with an
embedded data: URI and as .glb, indexed and not), a few hundred bytes each; OUT_DIR/mesh_repair/:
fixed pseudo-random byte strings (the target builds a soup from any bytes).
"""
import base64
import json
import os
import random
import struct
import sys

# A cube: 8 positions, 6 quads; texture coordinates per corner (six charts), normals per face.
P = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
QUADS = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
NORMALS = [(0, 0, -1), (0, 0, 1), (0, -1, 0), (0, 1, 0), (-1, 0, 0), (1, 0, 0)]
UV = [(0, 0), (1, 0), (1, 1), (0, 1)]
TRIS = [t for q in QUADS for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]


def obj_seeds():
    lines = ['mtllib cube.mtl']
    lines += ['v %g %g %g %g %g %g' % (p + (p[0], p[1], 0.5)) for p in P]
    lines += ['vt %g %g' % t for t in UV]
    lines += ['vn %g %g %g' % n for n in NORMALS]
    for f, q in enumerate(QUADS):
        if f in (0, 3):
            lines.append('usemtl %s' % ('red' if f == 0 else 'blue'))
        lines.append('f ' + ' '.join('%d/%d/%d' % (v + 1, k + 1, f + 1) for k, v in enumerate(q)))
    plain = ['v %g %g %g' % p for p in P] + ['f ' + ' '.join(str(v - 8) for v in q) for q in QUADS]
    return {'cube': '\n'.join(lines) + '\n', 'negative': '\n'.join(plain) + '\n',
            'vn-only': 'v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n'}


def off_seeds():
    ascii_off = 'OFF\n8 6 0\n' + ''.join('%g %g %g\n' % p for p in P) + \
        ''.join('4 %d %d %d %d\n' % q for q in QUADS)
    coff = 'COFF\n8 12 0\n' + ''.join('%g %g %g 1 0 0 1\n' % p for p in P) + \
        ''.join('3 %d %d %d\n' % t for t in TRIS)

    def binary(endian, colours):
        b = b'OFF BINARY\n' + struct.pack(endian + '3i', 8, 6, 0)
        b += b''.join(struct.pack(endian + '3f', *p) for p in P)
        for q in QUADS:
            b += struct.pack(endian + '5i', 4, *q) + (struct.pack(endian + 'i', 0) if colours else b'')
        return b
    return {'quads': ascii_off, 'coff': coff, 'binary-le': binary('<', False),
            'binary-be': binary('>', True)}


def ply_seeds():
    def header(fmt, extra_vertex, extra_face, nv, nf):
        return ('ply\nformat %s 1.0\ncomment TextureFile cube.png\nelement vertex %d\n'
                'property float x\nproperty float y\nproperty float z\n%s'
                'element face %d\nproperty list uchar int vertex_indices\n%send_header\n'
                % (fmt, nv, extra_vertex, nf, extra_face))
    vprops = ('property float nx\nproperty float ny\nproperty float nz\n'
              'property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n'
              'property float s\nproperty float t\n')
    fprops = 'property list uchar float texcoord\nproperty int texnumber\n'
    ascii_ply = header('ascii', vprops, fprops, 8, 6)
    for p in P:
        ascii_ply += '%g %g %g 0 0 1 255 128 0 255 %g %g\n' % (p + (p[0], p[1]))
    for q in QUADS:
        ascii_ply += '4 %d %d %d %d 8 0 0 1 0 1 1 0 1 0\n' % q
    binary = header('binary_little_endian', vprops, '', 8, 6).encode()
    for p in P:
        binary += struct.pack('<6f4B2f', *p, 0, 0, 1, 255, 128, 0, 255, p[0], p[1])
    for q in QUADS:
        binary += struct.pack('<B4i', 4, *q)
    big = header('binary_big_endian', '', '', 8, 6).encode()
    big += b''.join(struct.pack('>3f', *p) for p in P)
    big += b''.join(struct.pack('>B4i', 4, *q) for q in QUADS)
    return {'ascii': ascii_ply, 'binary-le': binary, 'binary-be': big}


def stl_seeds():
    text = 'solid cube\n'
    for t in TRIS:
        text += 'facet normal 0 0 0\nouter loop\n' + \
            ''.join('vertex %g %g %g\n' % P[v] for v in t) + 'endloop\nendfacet\n'
    text += 'endsolid cube\n'
    binary = b'\0' * 80 + struct.pack('<I', len(TRIS))
    for t in TRIS:
        binary += struct.pack('<3f', 0, 0, 0) + b''.join(struct.pack('<3f', *P[v]) for v in t) + b'\0\0'
    return {'ascii': text, 'binary': binary}


def gltf_seeds():
    # Split vertices (24: one per quad corner), as glTF exporters write them.
    pos, nrm, uv, col, idx = b'', b'', b'', b'', []
    for f, q in enumerate(QUADS):
        for k, v in enumerate(q):
            pos += struct.pack('<3f', *P[v])
            nrm += struct.pack('<3f', *NORMALS[f])
            uv += struct.pack('<2f', *UV[k])
            col += struct.pack('<4B', 255, 64 * (f % 4), 0, 255)
        idx += [f * 4, f * 4 + 1, f * 4 + 2, f * 4, f * 4 + 2, f * 4 + 3]
    ind = struct.pack('<36H', *idx)
    data = pos + nrm + uv + col + ind
    views = [(0, len(pos)), (len(pos), len(nrm)), (len(pos) + len(nrm), len(uv)),
             (len(pos) + len(nrm) + len(uv), len(col)), (len(data) - len(ind), len(ind))]
    doc = {
        'asset': {'version': '2.0'},
        'scene': 0, 'scenes': [{'nodes': [0]}],
        'nodes': [{'children': [1], 'scale': [2, 2, 2]}, {'mesh': 0, 'translation': [1, 0, 0]}],
        'meshes': [{'primitives': [
            {'attributes': {'POSITION': 0, 'NORMAL': 1, 'TEXCOORD_0': 2, 'COLOR_0': 3},
             'indices': 4, 'material': 0},
            {'attributes': {'POSITION': 0}, 'indices': 5, 'material': 1, 'mode': 4}]}],
        'materials': [{'name': 'tex', 'pbrMetallicRoughness': {'baseColorTexture': {'index': 0}}},
                      {'name': 'plain', 'pbrMetallicRoughness': {'baseColorFactor': [1, 0, 0, 1]}}],
        'textures': [{'source': 0}], 'images': [{'uri': 'cube.png'}],
        'accessors': [
            {'bufferView': 0, 'componentType': 5126, 'count': 24, 'type': 'VEC3',
             'min': [0, 0, 0], 'max': [1, 1, 1]},
            {'bufferView': 1, 'componentType': 5126, 'count': 24, 'type': 'VEC3'},
            {'bufferView': 2, 'componentType': 5126, 'count': 24, 'type': 'VEC2'},
            {'bufferView': 3, 'componentType': 5121, 'normalized': True, 'count': 24, 'type': 'VEC4'},
            {'bufferView': 4, 'componentType': 5123, 'count': 18, 'type': 'SCALAR'},
            {'bufferView': 4, 'byteOffset': 36, 'componentType': 5123, 'count': 18, 'type': 'SCALAR'}],
        'bufferViews': [{'buffer': 0, 'byteOffset': o, 'byteLength': n} for o, n in views],
    }
    embedded = dict(doc, buffers=[{'byteLength': len(data), 'uri': 'data:application/octet-stream;base64,'
                                   + base64.b64encode(data).decode()}])
    text = json.dumps(embedded, separators=(',', ':'))
    glb_doc = dict(doc, buffers=[{'byteLength': len(data)}])
    j = json.dumps(glb_doc, separators=(',', ':')).encode()
    j += b' ' * (-len(j) % 4)
    bin_chunk = data + b'\0' * (-len(data) % 4)
    glb = struct.pack('<4sII', b'glTF', 2, 12 + 8 + len(j) + 8 + len(bin_chunk))
    glb += struct.pack('<I4s', len(j), b'JSON') + j + struct.pack('<I4s', len(bin_chunk), b'BIN\0') + bin_chunk
    strip = dict(embedded)
    strip['meshes'] = [{'primitives': [{'attributes': {'POSITION': 0}, 'mode': 5}]}]
    return {'cube-embedded': text, 'cube-glb': glb, 'strip': json.dumps(strip)}


def repair_seeds():
    rng = random.Random(14)
    return {'random-%d' % n: bytes(rng.randrange(256) for _ in range(n)) for n in (64, 512, 4096)}


def main():
    out_dir = sys.argv[1]
    for fmt, seeds in (('obj', obj_seeds()), ('off', off_seeds()), ('ply', ply_seeds()),
                       ('stl', stl_seeds()), ('gltf', gltf_seeds()), ('repair', repair_seeds())):
        d = os.path.join(out_dir, 'mesh_' + fmt)
        os.makedirs(d, exist_ok=True)
        for name, data in seeds.items():
            with open(os.path.join(d, name), 'wb') as out:
                out.write(data.encode() if isinstance(data, str) else data)


if __name__ == '__main__':
    main()
