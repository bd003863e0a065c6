#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""A UV sphere as OBJ for the attribute decode-speed target (a textured ~100k-face
asset against its geometry-only stream): rings x segments, a texture seam at u = 0 / 1, one
texture coordinate per pole triangle, smooth normals (one per vertex). The same layout as
tests/meshio/test_mesh_attributes.cpp's uv_sphere(). --plain writes positions and faces only.

  python3 tests/bench/uv_sphere.py /tmp/sphere.obj [--rings 225 --segments 222] [--plain]
(225 x 222: 99,456 faces.)
"""
import argparse
import math


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--rings", type=int, default=225)
    ap.add_argument("--segments", type=int, default=222)
    ap.add_argument("--plain", action="store_true", help="positions and faces only")
    a = ap.parse_args()
    rings, seg = a.rings, a.segments
    L = []
    def vertex(x, y, z):
        L.append(f"v {x:.9g} {y:.9g} {z:.9g}")
        if not a.plain:
            L.append(f"vn {x:.9g} {y:.9g} {z:.9g}")
    vertex(0, 0, 1)
    for i in range(1, rings):
        for j in range(seg):
            t, p = math.pi * i / rings, 2 * math.pi * j / seg
            vertex(math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t))
    vertex(0, 0, -1)
    if not a.plain:
        for i in range(1, rings):
            for j in range(seg + 1):
                L.append(f"vt {j / seg:.9g} {1 - i / rings:.9g}")
        for pole in range(2):
            for j in range(seg):
                L.append(f"vt {(j + 0.5) / seg:.9g} {0 if pole else 1}")
    pole_uv = 1 + (rings - 1) * (seg + 1)
    vid = lambda i, j: 2 + (i - 1) * seg + j % seg
    tid = lambda i, j: 1 + (i - 1) * (seg + 1) + j
    south = 2 + (rings - 1) * seg
    def face(*c):
        if a.plain:
            L.append("f " + " ".join(str(c[k]) for k in (0, 2, 4)))
        else:
            L.append("f " + " ".join(f"{c[k]}/{c[k + 1]}/{c[k]}" for k in (0, 2, 4)))
    for j in range(seg):
        face(1, pole_uv + j, vid(1, j), tid(1, j), vid(1, j + 1), tid(1, j + 1))
    for i in range(1, rings - 1):
        for j in range(seg):
            face(vid(i, j), tid(i, j), vid(i + 1, j), tid(i + 1, j), vid(i + 1, j + 1),
                 tid(i + 1, j + 1))
            face(vid(i, j), tid(i, j), vid(i + 1, j + 1), tid(i + 1, j + 1), vid(i, j + 1),
                 tid(i, j + 1))
    for j in range(seg):
        face(vid(rings - 1, j), tid(rings - 1, j), south, pole_uv + seg + j, vid(rings - 1, j + 1),
             tid(rings - 1, j + 1))
    with open(a.out, "w") as f:
        f.write("\n".join(L) + "\n")


if __name__ == "__main__":
    main()
