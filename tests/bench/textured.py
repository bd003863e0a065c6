#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The textured benchmark: meshes with texture coordinates, normals, colours and
materials; pmz against Draco (size) and gltfpack (simplification), and pmz's attribute-aware
simplification against its own geometry-only run.

The set (nothing is committed; everything is made here from the corpus):
  - corpus meshes given real-ish attributes by bench-add-attributes (per-chart box-projected
    texture coordinates with seams, normals smooth within 60-degree creases, and on every
    other mesh curvature colours);
  - the assimp-testmodels samples big enough to simplify (10k+ faces; Debian's package has one,
    2CylinderEngine.glb: normals and 34 materials).
Each mesh exists as NAME.glb (simplifiers, comparisons) and NAME.obj (+ .mtl) for the codecs
(draco_encoder reads OBJ; its OBJ reader has no vertex colours, so the .obj holds texture
coordinates, normals and materials, and pmz is given the same file).

  (a) size: pmz-encode NAME.obj (when the writer codes attributes) against
      draco_encoder -qp 14 -qt 12 -qn 10 -qg 8 -cl 10 (pmz's defaults are the same precision:
      positions 14 bits, texture coordinates 12, normals 10, colours 8).
  (b) at 10% and 2%: gltfpack -si R -noq (npm gltfpack, scripts/install_gltfpack.sh) and
      pmz-simplify to gltfpack's face count; texture-space error (pmz-compare: |delta uv| at
      corresponding points) and geometric mean error (symmetric, / bbox diagonal).
  (c) pmz-simplify --attributes full (default) against --attributes geometry-only at the
      same face count: geometric mean error ratio (target <= 1.10).
Errors and sizes are deterministic (one run each); simplification times are medians of
--repeat alternating runs, with the load noted.

Usage: python3 tests/bench/textured.py [--build build] [--out bench-out/textured] [--quick]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
# (corpus mesh, with colours): CAD, organic, scans; 13k to 75k faces.
CORPUS = [("fandisk", False), ("blade", True), ("camel", False), ("ChineseDragon-10kv", True),
          ("mannequin-devil", False), ("man", True), ("armadillo", False), ("bunny00", True)]
QUICK = [("fandisk", False), ("camel", True)]
ASSIMP = ["glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb"]
RATIOS = [0.1, 0.02]


def run(cmd, **kw):
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))}: {r.stderr.strip() or r.stdout.strip()}")
    return r


def compare(build, original, other):
    j = json.loads(run([build / "bin/pmz-compare", original, other, "--json"]).stdout)
    a = j.get("attributes", {})
    return dict(faces=j["faces_other"], mean=j["mean"], max=j["max"],
                texcoord=a.get("texcoord", {}).get("mean"),
                normal=a.get("normal_degrees", {}).get("mean"),
                color=a.get("color", {}).get("mean"))


def simplify(build, src, out, faces, mode):
    t0 = time.perf_counter()
    run([build / "bin/pmz-simplify", src, "-o", out, "--faces", faces, "--attributes", mode,
         "--quiet"])
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default="bench-out/textured")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeat", type=int, default=3, help="alternating timing runs")
    ap.add_argument("--size-only", action="store_true", help="only (a): encode and compare sizes")
    ap.add_argument("--report", help="only rewrite the report from this textured.json")
    args = ap.parse_args()
    build = Path(args.build).resolve()
    out = Path(args.out).resolve()
    if args.report:
        data = json.loads(Path(args.report).read_text())
        ratios = [x for x in RATIOS if f"{int(x * 100)}%" in data["results"][0]]
        write_report(out / "textured.md", data["results"], data["load"], ratios)
        print((out / "textured.md").read_text())
        return
    (out / "set").mkdir(parents=True, exist_ok=True)
    gltfpack = build / "gltfpack/node_modules/.bin/gltfpack"
    if not gltfpack.exists():
        run(["bash", ROOT / "scripts/install_gltfpack.sh", build])
    meshes = []
    for name, colors in (QUICK if args.quick else CORPUS):
        src = ROOT / "corpus" / f"{name}.off"
        if not src.exists():
            print(f"textured: {src} missing (bash scripts/fetch_corpus.sh build); skipped")
            continue
        glb, obj = out / "set" / f"{name}.glb", out / "set" / f"{name}.obj"
        info = json.loads(run([build / "bench/bench-add-attributes", src, glb] +
                              (["--colors"] if colors else [])).stdout)
        run([build / "bench/bench-add-attributes", src, obj])  # no colours: Draco's OBJ has none
        meshes.append(dict(name=name, glb=glb, obj=obj, faces=info["faces"],
                           wedges=info["wedges"], vertices=info["vertices"],
                           attributes="uv, normals" + (", colours" if colors else "")))
    if not args.quick:
        for rel in ASSIMP:
            src = ROOT / "corpus-assimp" / rel
            if not src.exists():
                print(f"textured: {src} missing (scripts/fetch_assimp_models.sh); skipped")
                continue
            name = Path(rel).stem
            glb, obj = out / "set" / f"{name}.glb", out / "set" / f"{name}.obj"
            # Through pmz's reader once (repair, welding), so every tool gets the same mesh.
            for dst in (glb, obj):
                r = run([build / "bin/pmz-simplify", src, "-o", dst, "--ratio", "1", "--quiet"])
            faces = int(r.stdout.split(" -> ")[1].split()[0])
            meshes.append(dict(name=name, glb=glb, obj=obj, faces=faces, wedges=None,
                               vertices=None, attributes="normals, 34 materials (assimp sample)"))

    load = os.getloadavg()[0]
    results = []
    for m in meshes:
        print(f"textured: {m['name']} ({m['faces']} faces)", flush=True)
        work = out / m["name"]
        work.mkdir(exist_ok=True)
        row = dict(name=m["name"], faces=m["faces"], attributes=m["attributes"],
                   wedges=m["wedges"], vertices=m["vertices"])
        # (a) sizes.
        drc = work / "full.drc"
        run(["draco_encoder", "-i", m["obj"], "-o", drc, "-qp", "14", "-qt", "12", "-qn", "10",
             "-qg", "8", "-cl", "10"])
        row["draco_bytes"] = drc.stat().st_size
        pmz = work / "full.pmz"
        r = run([build / "bin/pmz-encode", m["obj"], "-o", pmz, "--quiet"])
        row["pmz_codes_attributes"] = "attributes not encoded" not in r.stderr
        row["pmz_bytes"] = pmz.stat().st_size
        # (b) and (c) per ratio.
        for ratio in [] if args.size_only else RATIOS:
            key = f"{int(ratio * 100)}%"
            gp = work / f"gltfpack-{key}.glb"
            run([gltfpack, "-i", m["glb"], "-o", gp, "-si", ratio, "-noq"])
            g = compare(build, m["glb"], gp)
            full = work / f"pmz-{key}-gp.glb"
            simplify(build, m["glb"], full, g["faces"], "full")
            p = compare(build, m["glb"], full)
            # (c): at the nominal ratio; geometry-only to the count the full run reached.
            nominal = max(1, round(ratio * m["faces"]))
            full_n, geo_n = work / f"pmz-{key}-full.glb", work / f"pmz-{key}-geometry.glb"
            times = {"full": [], "geometry-only": []}
            for rep in range(args.repeat):  # alternating; the outputs are the same every time
                times["full"].append(simplify(build, m["glb"], full_n, nominal, "full"))
                fn = compare(build, m["glb"], full_n) if rep == 0 else fn
                times["geometry-only"].append(
                    simplify(build, m["glb"], geo_n, fn["faces"], "geometry-only"))
            gn = compare(build, m["glb"], geo_n)
            row[key] = dict(gltfpack=g, pmz=p, full=fn, geometry=gn,
                            seconds_full=statistics.median(times["full"]),
                            seconds_geometry=statistics.median(times["geometry-only"]))
        results.append(row)
    (out / "textured.json").write_text(json.dumps(dict(load=load, results=results), indent=1))
    write_report(out / "textured.md", results, load, [] if args.size_only else RATIOS)
    print((out / "textured.md").read_text())


# Relative errors below this are both "exact" (blade's planar faces): no meaningful ratio.
EXACT = 1e-6


def ratio_text(a, b):
    if a is not None and b is not None and a < EXACT and b < EXACT:
        return "both < 1e-6"
    return f"{a / b:.3f}" if a is not None and b else "n/a"


def write_report(path, results, load, ratios):
    L = []
    L.append(f"Load average at the start: {load:.1f} (2 cores). Relative geometric errors (/ bbox "
             "diagonal), texture error in uv units (mean |delta uv| at corresponding points). "
             "Ratios where both errors are below 1e-6 (exact) are left out of the medians.\n")
    L.append("### (a) Size: pmz-encode vs draco_encoder -qp 14 -qt 12 -qn 10 -qg 8 -cl 10\n")
    L.append("| mesh | faces | attributes | Draco bytes | pmz bytes | pmz / Draco |")
    L.append("|---|---:|---|---:|---:|---:|")
    size_ratios = []
    for r in results:
        coded = r["pmz_codes_attributes"]
        ratio = r["pmz_bytes"] / r["draco_bytes"]
        if coded:
            size_ratios.append(ratio)
        L.append(f"| {r['name']} | {r['faces']} | {r['attributes'].replace(', colours', '')} | "
                 f"{r['draco_bytes']} | "
                 f"{r['pmz_bytes']}{'' if coded else ' (geometry only)'} | "
                 f"{f'{ratio:.3f}' if coded else 'n/a'} |")
    if size_ratios:
        L.append(f"\nMedian pmz / Draco: {statistics.median(size_ratios):.3f} (target <= 1.25)\n")
    else:
        L.append("\npmz-encode does not code attributes yet: no size ratio (the .pmz column "
                 "holds geometry only).\n")
    for key in [f"{int(x * 100)}%" for x in ratios]:
        L.append(f"### (b) {key}: pmz-simplify vs gltfpack -si {float(key[:-1]) / 100} -noq, "
                 "same face count\n")
        L.append("| mesh | gltfpack faces | pmz faces | texture err gltfpack | texture err pmz | "
                 "pmz / gltfpack | geo mean gltfpack | geo mean pmz | pmz / gltfpack |")
        L.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        tex, geo = [], []
        for r in results:
            g, p = r[key]["gltfpack"], r[key]["pmz"]
            if g["texcoord"] is not None and p["texcoord"] is not None and \
                    max(g["texcoord"], p["texcoord"]) >= EXACT:
                tex.append(p["texcoord"] / g["texcoord"])
            if p["mean"] >= EXACT or g["mean"] >= EXACT:
                geo.append(p["mean"] / g["mean"])
            t = lambda x: "n/a" if x is None else f"{x:.3e}"
            L.append(f"| {r['name']} | {g['faces']} | {p['faces']} | {t(g['texcoord'])} | "
                     f"{t(p['texcoord'])} | {ratio_text(p['texcoord'], g['texcoord'])} | "
                     f"{g['mean']:.3e} | {p['mean']:.3e} | {ratio_text(p['mean'], g['mean'])} |")
        if tex:
            L.append(f"\nTexture error pmz / gltfpack: median {statistics.median(tex):.3f}, "
                     f"pmz at or below on {sum(x <= 1 for x in tex)} of {len(tex)}. ")
        L.append(f"Geometric mean error pmz / gltfpack: median {statistics.median(geo):.3f}, "
                 f"pmz ahead on {sum(x < 1 for x in geo)} of {len(geo)}.\n")
    if not ratios:
        path.write_text("\n".join(L) + "\n")
        return
    L.append("### (c) Attribute-aware (default) vs geometry-only pmz-simplify, same face count\n")
    L.append("| mesh | ratio | faces | geo mean geometry-only | geo mean full | full / geometry | "
             "texture err geometry-only | texture err full | time geometry-only s | time full s |")
    L.append("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for key in [f"{int(x * 100)}%" for x in ratios]:
        c = []
        for r in results:
            f, g = r[key]["full"], r[key]["geometry"]
            if f["mean"] >= EXACT or g["mean"] >= EXACT:
                c.append(f["mean"] / g["mean"])
            t = lambda x: "n/a" if x is None else f"{x:.3e}"
            L.append(f"| {r['name']} | {key} | {f['faces']} | {g['mean']:.3e} | {f['mean']:.3e} | "
                     f"{ratio_text(f['mean'], g['mean'])} | {t(g['texcoord'])} | "
                     f"{t(f['texcoord'])} | {r[key]['seconds_geometry']:.2f} | "
                     f"{r[key]['seconds_full']:.2f} |")
        L.append(f"| **median {key}** | | | | | **{statistics.median(c):.3f}** "
                 f"(max {max(c):.3f}) | | | | |")
    path.write_text("\n".join(L) + "\n")


if __name__ == "__main__":
    sys.exit(main())
