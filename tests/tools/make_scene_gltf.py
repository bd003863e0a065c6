#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes a small glTF scene of several meshes for pmz-encode's scene GLB.

    make_scene_gltf.py OUT_DIR

OUT_DIR/scene.gltf with its buffer scene.bin and texture checker.png beside it, and
OUT_DIR/scene.json: each mesh's name and face count. Meshes: "ring" (a torus with normals, one
metallic material with an extension), "tube" (a torus with texture coordinates, two primitives
of two materials, one textured through a sampler) and "sheet" (an open grid without a material).
Nodes: a root with a translation whose children are two instances of "ring" (rotation, scale),
"tube" (a matrix) and "sheet"; the default scene is the second of two scenes. Everything is
computed here, so the files are the same on every run.
"""
import json
import math
import os
import struct
import sys
import zlib


def png(width, height, pixel):
    """A small valid RGB PNG; pixel(x, y) gives each pixel's colour."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    raw = b"".join(b"\0" + b"".join(bytes(pixel(x, y)) for x in range(width)) for y in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def torus(rings, sides, big, small, seam):
    """Positions, normals, texture coordinates and triangles of a torus; with `seam` the last
    column and row repeat the first (their own texture coordinates)."""
    cols, rows = rings + seam, sides + seam
    pos, nrm, uv, tris = [], [], [], []
    for i in range(cols):
        a = 2 * math.pi * i / rings
        for j in range(rows):
            b = 2 * math.pi * j / sides
            n = (math.cos(a) * math.cos(b), math.sin(a) * math.cos(b), math.sin(b))
            c = (big * math.cos(a), big * math.sin(a), 0.0)
            pos.append(tuple(c[k] + small * n[k] for k in range(3)))
            nrm.append(n)
            uv.append((i / rings, j / sides))
    for i in range(rings):
        for j in range(sides):
            i1, j1 = (i + 1) % cols, (j + 1) % rows
            v00, v10, v01, v11 = i * rows + j, i1 * rows + j, i * rows + j1, i1 * rows + j1
            tris += [(v00, v10, v11), (v00, v11, v01)]
    return pos, nrm, uv, tris


def grid(n, size):
    """An open n x n grid of quads in the z = 0 plane, two triangles each."""
    pos = [(size * (i / n - 0.5), size * (j / n - 0.5), 0.0) for i in range(n + 1) for j in range(n + 1)]
    tris = []
    for i in range(n):
        for j in range(n):
            v = i * (n + 1) + j
            tris += [(v, v + n + 1, v + n + 2), (v, v + n + 2, v + 1)]
    return pos, tris


class Blob:
    """The buffer and the views and accessors over it."""
    def __init__(self):
        self.data, self.views, self.accessors = bytearray(), [], []

    def add(self, values, kind, component, target):
        n = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}[kind]
        flat = [x for v in values for x in (v if n > 1 else (v,))]
        fmt = "f" if component == 5126 else "H"
        while len(self.data) % 4:
            self.data.append(0)
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": 4 * len(flat) if fmt == "f" else 2 * len(flat),
                "target": target}
        self.data += struct.pack(f"<{len(flat)}{fmt}", *flat)
        self.views.append(view)
        acc = {"bufferView": len(self.views) - 1, "componentType": component, "count": len(values), "type": kind}
        if kind == "VEC3" and component == 5126:
            acc["min"] = [min(v[k] for v in values) for k in range(3)]
            acc["max"] = [max(v[k] for v in values) for k in range(3)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def vertices(self, pos, nrm=None, uv=None):
        attributes = {"POSITION": self.add(pos, "VEC3", 5126, 34962)}
        if nrm:
            attributes["NORMAL"] = self.add(nrm, "VEC3", 5126, 34962)
        if uv:
            attributes["TEXCOORD_0"] = self.add(uv, "VEC2", 5126, 34962)
        return attributes

    def primitive(self, attributes, tris, material=None):
        p = {"attributes": attributes, "indices": self.add([i for t in tris for i in t], "SCALAR", 5123, 34963)}
        if material is not None:
            p["material"] = material
        return p


def make(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    blob = Blob()
    ring_pos, ring_nrm, _, ring_tris = torus(16, 8, 1.0, 0.3, 0)
    ring = {"name": "ring", "primitives": [blob.primitive(blob.vertices(ring_pos, ring_nrm), ring_tris, 0)]}
    tube_pos, tube_nrm, tube_uv, tube_tris = torus(20, 10, 0.8, 0.2, 1)
    half = len(tube_tris) // 2
    tube_attributes = blob.vertices(tube_pos, tube_nrm, tube_uv)
    tube = {"name": "tube", "primitives": [blob.primitive(tube_attributes, tube_tris[:half], 1),
                                           blob.primitive(tube_attributes, tube_tris[half:], 2)]}
    sheet_pos, sheet_tris = grid(6, 2.0)
    sheet = {"name": "sheet", "primitives": [blob.primitive(blob.vertices(sheet_pos), sheet_tris)]}
    gltf = {
        "asset": {"version": "2.0", "generator": "tests/tools/make_scene_gltf.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength", "KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 2.0}]}},
        "scene": 1,
        "scenes": [{"name": "unused", "nodes": [5]}, {"name": "scene", "nodes": [0]}],
        "nodes": [
            {"name": "root", "translation": [0.5, 0.0, -1.0], "children": [1, 2, 3, 4]},
            {"name": "ring-a", "mesh": 0, "rotation": [0.0, 0.0, 0.38268343, 0.92387953]},
            {"name": "ring-b", "mesh": 0, "scale": [0.5, 0.5, 0.5], "translation": [3.0, 0.0, 0.0]},
            {"name": "tube-node", "mesh": 1,
             "matrix": [1, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 2.5, 0, 1]},
            {"name": "sheet-node", "mesh": 2, "translation": [0.0, 0.0, -0.5],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "elsewhere", "mesh": 2},
        ],
        "meshes": [ring, tube, sheet],
        "materials": [
            {"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.8, 0.3, 1.0],
                                                      "metallicFactor": 0.9, "roughnessFactor": 0.25},
             "emissiveFactor": [0.1, 0.05, 0.0],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}}},
            {"name": "checker", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                         "metallicFactor": 0.0},
             "doubleSided": True},
            {"name": "blue", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.3, 0.9, 1.0],
                                                      "metallicFactor": 0.1, "roughnessFactor": 0.6}},
        ],
        "textures": [{"sampler": 0, "source": 0}],
        "samplers": [{"magFilter": 9728, "minFilter": 9984, "wrapS": 33071, "wrapT": 33648}],
        "images": [{"uri": "checker.png", "name": "checker"}],
        "accessors": blob.accessors,
        "bufferViews": blob.views,
        "buffers": [{"uri": "scene.bin", "byteLength": len(blob.data)}],
    }
    with open(os.path.join(out_dir, "scene.bin"), "wb") as f:
        f.write(blob.data)
    with open(os.path.join(out_dir, "checker.png"), "wb") as f:
        f.write(png(8, 8, lambda x, y: (230, 230, 230) if (x + y) % 2 else (40, 40, 40)))
    with open(os.path.join(out_dir, "scene.gltf"), "w") as f:
        json.dump(gltf, f, indent=1)
    faces = {"ring": len(ring_tris), "tube": len(tube_tris), "sheet": len(sheet_tris)}
    with open(os.path.join(out_dir, "scene.json"), "w") as f:
        json.dump({"faces": faces}, f)
    return gltf, faces


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    make(sys.argv[1])
