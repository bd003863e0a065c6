#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Cross-checks pmz-compare against MeshLab's "Hausdorff Distance" filter (meshlabserver,
headless under xvfb-run) on real meshes against simplified versions of them.

MeshLab's filter is one-sided, so it runs both ways. Mean: face samples only (Montecarlo,
area-proportional, what pmz-compare's mean is). Max: vertices + edges + faces.
Usage: tests/bench/meshlab_crosscheck.py --build DIR [--out DIR] [--corpus DIR]
Needs: apt-get install meshlab xvfb.
"""
import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
PAIRS = [("fandisk", 0.1), ("bunny00", 0.02), ("camel", 0.1), ("lion-head", 0.05), ("armadillo", 0.02)]

MLX = """<!DOCTYPE FilterScript>
<FilterScript>
 <filter name="Hausdorff Distance">
  <Param type="RichMesh" value="{sampled}" name="SampledMesh"/>
  <Param type="RichMesh" value="{target}" name="TargetMesh"/>
  <Param type="RichBool" value="false" name="SaveSample"/>
  <Param type="RichBool" value="{vert}" name="SampleVert"/>
  <Param type="RichBool" value="{vert}" name="SampleEdge"/>
  <Param type="RichBool" value="false" name="SampleFauxEdge"/>
  <Param type="RichBool" value="true" name="SampleFace"/>
  <Param type="RichInt" value="{samples}" name="SampleNum"/>
  <Param type="RichAbsPerc" value="1e6" min="0" max="1e6" name="MaxDist"/>
 </filter>
</FilterScript>
"""


def meshlab(a, b, sampled, vert, samples):
    """One-sided distance from mesh `sampled` (0: a, 1: b) to the other; absolute (max, mean)."""
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "h.mlx"
        script.write_text(MLX.format(sampled=sampled, target=1 - sampled, vert=str(vert).lower(), samples=samples))
        p = subprocess.run(["xvfb-run", "-a", "meshlabserver", "-i", str(a), "-i", str(b), "-s", str(script)],
                           capture_output=True, text=True, timeout=900)
    text = p.stdout + p.stderr
    m = re.search(r"min : ([0-9.e+-]+)\s+max ([0-9.e+-]+)\s+mean : ([0-9.e+-]+)", text)
    if not m:
        raise RuntimeError("meshlabserver gave no distances: " + text[-500:])
    return float(m.group(2)), float(m.group(3))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default=str(ROOT / "build"))
    ap.add_argument("--corpus", default=str(ROOT / "corpus"))
    ap.add_argument("--out", default=str(ROOT / "bench-out"))
    args = ap.parse_args()
    build, corpus, out = Path(args.build), Path(args.corpus), Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for name, ratio in PAIRS:
        orig = corpus / f"{name}.off"
        if not orig.exists():
            print(f"{orig} missing; skipped", file=sys.stderr)
            continue
        simp = out / "meshlab" / f"{name}-{ratio:g}.off"
        simp.parent.mkdir(parents=True, exist_ok=True)
        faces = int(open(orig).read(4096).split("OFF", 1)[1].split()[1])
        subprocess.run([str(build / "bench/bench-openmesh-decimate"), str(orig), str(simp), str(round(ratio * faces))],
                       check=True, capture_output=True)
        ours = json.loads(subprocess.run([str(build / "bin/pmz-compare"), str(orig), str(simp), "--json"],
                                         check=True, capture_output=True, text=True).stdout)
        samples = ours["forward"]["samples"]  # same order of magnitude as ours
        fwd_max, _ = meshlab(orig, simp, 0, True, samples)
        bwd_max, _ = meshlab(orig, simp, 1, True, samples)
        _, fwd_mean = meshlab(orig, simp, 0, False, samples)
        _, bwd_mean = meshlab(orig, simp, 1, False, samples)
        ml_max, ml_mean = max(fwd_max, bwd_max), 0.5 * (fwd_mean + bwd_mean)
        row = dict(mesh=name, faces=faces, ratio=ratio, diag=ours["diag"], ours_mean=ours["mean_abs"],
                   ours_max=ours["max_abs"], ml_mean=ml_mean, ml_max=ml_max)
        rows.append(row)
        print(json.dumps(row), file=sys.stderr)
    lines = ["| mesh | faces | simplified to | pmz-compare mean | MeshLab mean | Δ mean | pmz-compare max "
             "| MeshLab max | Δ max |", "|---|---|---|---|---|---|---|---|---|"]
    ok = True
    for r in rows:
        dm = r["ours_mean"] / r["ml_mean"] - 1
        dx = r["ours_max"] / r["ml_max"] - 1
        ok &= abs(dm) <= 0.05 and abs(dx) <= 0.15
        d = r["diag"]
        lines.append(f"| {r['mesh']} | {r['faces']} | {r['ratio']:g} | {r['ours_mean'] / d:.4e} | "
                     f"{r['ml_mean'] / d:.4e} | {100 * dm:+.2f}% | {r['ours_max'] / d:.4e} | "
                     f"{r['ml_max'] / d:.4e} | {100 * dx:+.2f}% |")
    text = "\n".join(lines) + "\n"
    (out / "meshlab.md").write_text(text)
    print(text)
    return 0 if ok and rows else 1


if __name__ == "__main__":
    sys.exit(main())
