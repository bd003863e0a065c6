#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# Usage: textured_quick.py BUILD SET OUT [mesh,mesh,...]   (SET: textured.py OUT/set)
# Quick harness for two textured figures: per mesh and ratio, gltfpack -si R -noq, pmz-simplify to
# its face count (b); pmz-simplify at the nominal count, geometry-only at the count reached (c).
import json, subprocess, sys, statistics
from pathlib import Path
B = Path(sys.argv[1]).resolve(); SET = Path(sys.argv[2]); OUT = Path(sys.argv[3]); OUT.mkdir(exist_ok=True, parents=True)
GP = str(B / "gltfpack/node_modules/.bin/gltfpack")  # scripts/install_gltfpack.sh BUILD
names = sys.argv[4].split(",") if len(sys.argv) > 4 else ["fandisk","blade","camel","ChineseDragon-10kv","mannequin-devil","man","armadillo","bunny00"]
def run(c): 
    r = subprocess.run([str(x) for x in c], capture_output=True, text=True); assert r.returncode == 0, r.stderr; return r.stdout
def cmp(o, x):
    j = json.loads(run([B/"bin/pmz-compare", o, x, "--json"])); return j["faces_other"], j["mean"], j.get("attributes",{}).get("texcoord",{}).get("mean")
def simp(src, out, f, mode="full"): run([B/"bin/pmz-simplify", src, "-o", out, "--faces", f, "--attributes", mode, "--quiet"])
bs, cs = {0.1:[],0.02:[]}, {0.1:[],0.02:[]}
for n in names:
    src = SET/f"{n}.glb"; faces = cmp(src, src)[0]
    for r in (0.1, 0.02):
        k = f"{n}-{r}"; gp = OUT/f"{k}-gp.glb"
        if not gp.exists(): run([GP, "-i", src, "-o", gp, "-si", r, "-noq"])
        gf, gm, gt = cmp(src, gp)
        simp(src, OUT/f"{k}-pgp.glb", gf); pf, pm, pt = cmp(src, OUT/f"{k}-pgp.glb")
        simp(src, OUT/f"{k}-full.glb", max(1, round(r*faces))); ff, fm, ft = cmp(src, OUT/f"{k}-full.glb")
        simp(src, OUT/f"{k}-geo.glb", ff, "geometry-only"); _, om, _ = cmp(src, OUT/f"{k}-geo.glb")
        b = pt/gt if gt and gt > 1e-6 else None; c = fm/om if om > 1e-6 else None
        if b is not None: bs[r].append(b)
        if c is not None: cs[r].append(c)
        print(f"{n:20s} {int(r*100):2d}% b={b if b is None else round(b,3)} (pmz {pt} gp {gt} @{gf}) c={c if c is None else round(c,3)} geo/gp={round(pm/gm,3) if gm>1e-9 else None} faces {ff}", flush=True)
for r in (0.1, 0.02):
    if bs[r]: print(f"{int(r*100)}%: b median {statistics.median(bs[r]):.3f} max {max(bs[r]):.3f}; c median {statistics.median(cs[r]):.3f} max {max(cs[r]):.3f}")
