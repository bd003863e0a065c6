#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Makes the README's textured streaming screenshots (docs/images/viewer-textured.png).

  python3 scripts/textured_screenshots.py [--build build] [--mesh corpus/bunny00.off] [--out PNG]

Gives a corpus mesh real-ish attributes (six box-projection charts: texture coordinates with
seams where the charts meet, smooth normals, a checkerboard texture), encodes it with
pmz-encode, renders it with pmz-view --screenshot from the first 8% and 25% of its bytes and
from all of them (under xvfb-run), and puts the shots side by side. Standard library only.
The corpus comes from scripts/fetch_corpus.sh.
"""
import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile

# The viewer tests' PNG reader and writer (standard library only).
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "tests", "viewer"))
from viewer_test import read_png, write_png  # noqa: E402


def read_off(path):
    with open(path) as f:
        words = f.read().split()
    if not words[0].endswith("OFF"):
        sys.exit("%s: not an ASCII OFF file" % path)
    nv, nf = int(words[1]), int(words[2])
    at = 4
    vertices = []
    for _ in range(nv):
        vertices.append(tuple(float(x) for x in words[at:at + 3]))
        at += 3
    faces = []
    for _ in range(nf):
        n = int(words[at])
        corners = [int(x) for x in words[at + 1:at + 1 + n]]
        faces += [(corners[0], corners[k], corners[k + 1]) for k in range(1, n - 1)]
        at += 1 + n
    return vertices, faces


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def write_textured_obj(vertices, faces, directory, squares=6):
    """OBJ + MTL + PNG: each face's chart is the axis its normal points along most (six charts);
    a chart projects positions onto the other two axes, scaled so `squares` checker squares
    span the bounding box. Wedges: one vt per (vertex, chart), one vn per vertex."""
    lo = [min(v[i] for v in vertices) for i in range(3)]
    hi = [max(v[i] for v in vertices) for i in range(3)]
    size = max(hi[i] - lo[i] for i in range(3))
    normals = [[0.0, 0.0, 0.0] for _ in vertices]
    charts = []
    for a, b, c in faces:
        n = cross(sub(vertices[b], vertices[a]), sub(vertices[c], vertices[a]))
        for v in (a, b, c):
            for i in range(3):
                normals[v][i] += n[i]
        axis = max(range(3), key=lambda i: abs(n[i]))
        charts.append(2 * axis + (n[axis] < 0))
    texcoords, corner_texcoords = {}, []
    for (a, b, c), chart in zip(faces, charts):
        axis = chart // 2
        u_axis, v_axis = [i for i in range(3) if i != axis]
        for v in (a, b, c):
            key = (v, chart)
            if key not in texcoords:
                p = vertices[v]
                texcoords[key] = (len(texcoords) + 1, (p[u_axis] - lo[u_axis]) / size * squares / 8,
                                  (p[v_axis] - lo[v_axis]) / size * squares / 8)
            corner_texcoords.append(texcoords[key][0])
    with open(os.path.join(directory, "textured.obj"), "w") as f:
        f.write("mtllib textured.mtl\nusemtl checker\n")
        f.writelines("v %.6f %.6f %.6f\n" % v for v in vertices)
        for _, u, v in sorted(texcoords.values()):
            f.write("vt %.6f %.6f\n" % (u, v))
        for n in normals:
            length = math.sqrt(sum(x * x for x in n)) or 1.0
            f.write("vn %.6f %.6f %.6f\n" % tuple(x / length for x in n))
        for k, face in enumerate(faces):
            f.write("f " + " ".join("%d/%d/%d" % (v + 1, corner_texcoords[3 * k + j], v + 1)
                                    for j, v in enumerate(face)) + "\n")
    with open(os.path.join(directory, "textured.mtl"), "w") as f:
        f.write("newmtl checker\nKd 1 1 1\nmap_Kd checker.png\n")
    # 8x8 squares over 256 pixels: warm / cool alternating, hue drifting across the image so
    # neighbouring charts and stretched squares are easy to tell apart.
    rows = []
    for y in range(256):
        row = bytearray()
        for x in range(256):
            t = x / 255.0
            if (x // 32 + y // 32) % 2:
                row += bytes((235, int(120 + 100 * t), 40))
            else:
                row += bytes((40, int(90 + 120 * (1 - t)), 220))
        rows.append(row)
    write_png(os.path.join(directory, "checker.png"), 256, 256, rows)
    return os.path.join(directory, "textured.obj"), len(texcoords)


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", default=os.path.join(root, "build"))
    parser.add_argument("--mesh", default=os.path.join(root, "corpus", "bunny00.off"))
    parser.add_argument("--out", default=os.path.join(root, "docs", "images", "viewer-textured.png"))
    parser.add_argument("--fractions", default="0.08,0.25,1", help="fractions of the bytes, one shot each")
    parser.add_argument("--size", default="360x360")
    parser.add_argument("--yaw", default="20")
    args = parser.parse_args()
    for tool in ("pmz-encode", "pmz-view"):
        if not os.path.exists(os.path.join(args.build, "bin", tool)):
            sys.exit("%s not built in %s" % (tool, args.build))
    if not shutil.which("xvfb-run"):
        sys.exit("xvfb-run is missing (apt-get install xvfb xauth)")
    work = tempfile.mkdtemp(prefix="pmz-textured-")
    vertices, faces = read_off(args.mesh)
    obj, wedges = write_textured_obj(vertices, faces, work)
    pmz = os.path.join(work, "textured.pmz")
    run = subprocess.run([os.path.join(args.build, "bin", "pmz-encode"), obj, "-o", pmz], capture_output=True,
                         text=True)
    if run.returncode:
        sys.exit("pmz-encode failed: " + run.stderr.strip())
    print("%s: %d vertices, %d faces, %d wedges -> %s, %d bytes" % (args.mesh, len(vertices), len(faces), wedges,
                                                                    pmz, os.path.getsize(pmz)))
    size = os.path.getsize(pmz)
    shots = []
    for k, fraction in enumerate(float(x) for x in args.fractions.split(",")):
        png = os.path.join(work, "shot%d.png" % k)
        limit = [] if fraction >= 1 else ["--bytes", str(max(1, int(size * fraction)))]
        run = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", os.path.join(args.build, "bin", "pmz-view"),
                              pmz, "--screenshot", png, "--size", args.size, "--yaw", args.yaw] + limit,
                             capture_output=True, text=True)
        if run.returncode:
            sys.exit("pmz-view failed: " + run.stderr.strip())
        print(run.stdout.strip())
        width, height, channels, rows = read_png(png)
        shots.append((width, height, [row if channels == 3 else bytearray(
            b for x in range(width) for b in row[4 * x:4 * x + 3]) for row in rows]))
    gap = 8
    height = max(h for _, h, _ in shots)
    rows = []
    for y in range(height):
        row = bytearray()
        for k, (w, h, r) in enumerate(shots):
            if k:
                row += bytes((255, 255, 255)) * gap
            row += r[y] if y < h else bytes(3 * w)
        rows.append(row)
    width = sum(w for w, _, _ in shots) + gap * (len(shots) - 1)
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    write_png(args.out, width, height, rows)
    print("wrote %s (%dx%d)" % (args.out, width, height))
    shutil.rmtree(work)


if __name__ == "__main__":
    main()
