#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""What a view-dependent client fetches of a node stream (docs/benchmarks.md, "Decoding for a view").

  python3 tests/bench/view.py [--build build] [--compare] MESH STREAM.pmz

MESH is the stream's original (for the surface a camera shows), STREAM its .pmz with nodes. Two
kinds of view on a 1920x1080 viewport with a 60-degree field of view:
  whole:   from the front, back, left and above (y up), the camera fits the stream's bounding
           sphere in the view's height;
  closeup: from those four and the four upper corners of the box (45 degrees up from the front
           and back, left and right), the camera looks at the surface where the ray from the
           whole view's eye to a point half way from the centre to the box's side or corner
           first meets it, and moves in
           until it shows a tenth of MESH's surface (bench-view-surface --surface 0.1
           --onto-surface); where the ray misses the surface or no eye on that line shows a
           tenth (a terrain seen from below or edge-on), the view is printed as "view": "side"
           and left out of the close-ups' medians.
For each, `pmz-decode --camera ... --pixel-error P` reads the file by ranges at P = 1 and P = 0
(every node in view) and its bytes read are given as a fraction of the file's. With --compare,
each P = 1 result is measured against MESH by pmz-compare: its largest distance anywhere, in view
or not, in pixels at the target's depth (a bound of how far from the full resolution the view is
where it looks; the parts out of view stay coarse and may set it).
One JSON line per view, then the medians.
"""
import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile

FOV = 60.0
SIZE = (1920, 1080)


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"view.py: {' '.join(cmd)} failed: {r.stderr.strip()}")
    return r


def bounds(build, stream):
    out = run([f"{build}/bin/pmz-info", stream]).stdout
    m = re.search(r"bbox\s+\(([^)]*)\)\s*-\s*\(([^)]*)\)", out)
    if not m:
        sys.exit(f"view.py: no bbox in pmz-info's output for {stream}")
    return [float(x) for x in m.group(1).split()], [float(x) for x in m.group(2).split()]


def decode(build, stream, camera, pixel_error, out):
    err = run([f"{build}/bin/pmz-decode", stream, "--camera", camera, "--pixel-error",
               str(pixel_error), "-o", out]).stderr
    m = re.search(r"(\d+) of (\d+) nodes; read (\d+) of (\d+) bytes", err)
    if not m:
        sys.exit(f"view.py: unexpected pmz-decode output: {err.strip()}")
    nodes, total, read, size = (int(x) for x in m.groups())
    return {"nodes": nodes, "of_nodes": total, "bytes": read, "fraction": read / size}


def max_distance(build, mesh, other):
    r = run([f"{build}/bin/pmz-compare", mesh, other, "--json"])
    return json.loads(r.stdout)["max_abs"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--compare", action="store_true")
    ap.add_argument("mesh")
    ap.add_argument("stream")
    args = ap.parse_args()
    lo, hi = bounds(args.build, args.stream)
    centre = [(a + b) / 2 for a, b in zip(lo, hi)]
    radius = math.dist(lo, hi) / 2
    fit = radius / math.sin(math.radians(FOV / 2))
    directions = {"front": (0, 0, 1), "back": (0, 0, -1), "left": (-1, 0, 0), "above": (0, 1, 0.01),
                  "front-left": (-1, 1, 1), "front-right": (1, 1, 1), "back-left": (-1, 1, -1),
                  "back-right": (1, 1, -1)}
    corners = ("front-left", "front-right", "back-left", "back-right")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "view.ply")
        for name, d in directions.items():
            n = math.sqrt(sum(x * x for x in d))
            d = [x / n for x in d]
            eye = [c + fit * x for c, x in zip(centre, d)]
            cameras = {} if name in corners else {"whole": ",".join(f"{x:.6g}" for x in eye + centre)}
            # A point half way to the box's side (or corner) facing the eye.
            target = [c + 0.5 * x * (b - a) / 2 for c, x, a, b in zip(centre, d, lo, hi)]
            start = ",".join(f"{x:.6g}" for x in eye + target)
            r = subprocess.run([f"{args.build}/bench/bench-view-surface", args.mesh, start,
                                "--surface", "0.1", "--onto-surface"], capture_output=True, text=True)
            if r.returncode != 0 and "meets no face" not in r.stderr:
                sys.exit(f"view.py: bench-view-surface failed: {r.stderr.strip()}")
            found = json.loads(r.stdout) if r.returncode == 0 else {"camera": start, "visible": 0}
            # (bench-view-surface's search stops within a few percent of the fraction asked)
            closeup = "closeup" if found["visible"] >= 0.09 else "side"
            cameras[closeup] = found["camera"]
            for kind, camera in cameras.items():
                row = {"view": kind, "from": name, "camera": camera}
                if kind != "whole":
                    row["visible"] = found["visible"]
                for p in (1, 0):
                    row[f"p{p}"] = decode(args.build, args.stream, camera, p, out)
                    if p == 1 and args.compare:
                        c = [float(x) for x in camera.split(",")]
                        depth = math.dist(c[:3], c[3:])
                        pixel = 2 * depth * math.tan(math.radians(FOV / 2)) / SIZE[1]
                        row["p1"]["max_pixels"] = max_distance(args.build, args.mesh, out) / pixel
                print(json.dumps(row), flush=True)
                rows.append(row)
    for kind in ("whole", "closeup"):
        for p in (1, 0):
            fr = [r[f"p{p}"]["fraction"] for r in rows if r["view"] == kind]
            if not fr:
                print(f"{kind} P{p}: no such view")
                continue
            print(f"{kind} P{p}: median {statistics.median(fr):.1%} of the bytes "
                  f"(min {min(fr):.1%}, max {max(fr):.1%})")


if __name__ == "__main__":
    main()
