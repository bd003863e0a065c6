#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""pmz benchmark driver: runs pmz's tools and the peers side by side on the corpus, measures
error with pmz-compare, and writes a Markdown report and plots (error vs face ratio).

Entry point: tests/bench/run.sh (builds, fetches the corpus, calls this). Rows are data:
add a simplifier to SIMPLIFIERS or a codec to CODECS and it shows up in every table.
"""
import argparse
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent

# Corpus (scripts/fetch_corpus.sh documents why each one is here).
CORPUS = ["fandisk", "blade", "mech-holes-shark", "turbine", "cheese",  # CAD, creases, genus
          "bunny00", "armadillo", "lion-head", "mannequin-devil",       # scans (some open)
          "camel", "elephant", "ChineseDragon-10kv", "man",              # organic
          "elephant-with-holes"]                                         # many holes
BIG = "bunny00-loop2"  # two Loop subdivisions of bunny00: 1.2M faces
QUICK = ["fandisk", "camel", "lion-head"]
RATIOS = [0.5, 0.2, 0.1, 0.05, 0.02, 0.01]
BIG_RATIOS = [0.1, 0.01]
SUMMARY_RATIOS = [0.1, 0.02]
PEERS = ["openmesh-decimater", "meshopt-simplify"]  # the summary's ratios are to the better of these

# Simplifiers: cmd(build, input, output, faces) -> argv; the output has about `faces` faces.
# "prepare" (optional) runs once per mesh (e.g. encode a .pmz to decode prefixes of).
SIMPLIFIERS = {
    # The default metric: the paper's plus the Hausdorff guard (spec/algorithm.md section 6).
    "pmz-guarded": dict(
        tool="bin/pmz-simplify",
        cmd=lambda b, i, o, f, w: [b / "bin/pmz-simplify", i, "-o", o, "--faces", f, "--metric", "guarded"]),
    # The paper's metric alone.
    "pmz-multifeature": dict(
        tool="bin/pmz-simplify",
        cmd=lambda b, i, o, f, w: [b / "bin/pmz-simplify", i, "-o", o, "--faces", f, "--metric", "multifeature"]),
    "pmz-qem": dict(
        tool="bin/pmz-simplify",
        cmd=lambda b, i, o, f, w: [b / "bin/pmz-simplify", i, "-o", o, "--faces", f, "--metric", "qem"]),
    "pmz-prefix": dict(  # a prefix of the .pmz stream decoded to F faces (prefix fidelity)
        tool="bin/pmz-decode",
        needs=["bin/pmz-encode"],
        prepare=lambda b, i, w: [b / "bin/pmz-encode", i, "-o", w / "full.pmz"],
        cmd=lambda b, i, o, f, w: [b / "bin/pmz-decode", w / "full.pmz", "-o", o, "--faces", f]),
    # The same prefix from a lossless (--position-bits 0) stream: isolates what the split order costs
    # from what 14-bit quantization costs (on CAD meshes the latter is a sizeable part of the error).
    "pmz-prefix-lossless": dict(
        tool="bin/pmz-decode",
        needs=["bin/pmz-encode"],
        prepare=lambda b, i, w: [b / "bin/pmz-encode", i, "-o", w / "full-lossless.pmz", "--position-bits", "0"],
        cmd=lambda b, i, o, f, w: [b / "bin/pmz-decode", w / "full-lossless.pmz", "-o", o, "--faces", f]),
    "openmesh-decimater": dict(
        tool="bench/bench-openmesh-decimate",
        cmd=lambda b, i, o, f, w: [b / "bench/bench-openmesh-decimate", i, o, f]),
    "meshopt-simplify": dict(
        tool="bench/bench-meshopt-simplify",
        cmd=lambda b, i, o, f, w: [b / "bench/bench-meshopt-simplify", i, o, f]),
}

# Full-resolution codecs: encode(build, input_off, input_ply, output) and decode(build, file, out_ply).
CODECS = {
    "pmz (14 bits)": dict(
        tool="bin/pmz-encode", needs=["bin/pmz-decode"], ext=".pmz",
        encode=lambda b, off, ply, o: [b / "bin/pmz-encode", off, "-o", o, "--position-bits", "14"],
        decode=lambda b, i, o: [b / "bin/pmz-decode", i, "-o", o]),
    # The speed level: simpler models, faster to decode, larger.
    "pmz level 1 (14 bits)": dict(
        tool="bin/pmz-encode", needs=["bin/pmz-decode"], ext=".pmz",
        encode=lambda b, off, ply, o: [b / "bin/pmz-encode", off, "-o", o, "--position-bits", "14",
                                       "--level", "1"],
        decode=lambda b, i, o: [b / "bin/pmz-decode", i, "-o", o]),
    "draco -qp 14 -cl 10": dict(
        tool="/usr/bin/draco_encoder", needs=["/usr/bin/draco_decoder"], ext=".drc",
        encode=lambda b, off, ply, o: ["/usr/bin/draco_encoder", "-i", ply, "-o", o, "-qp", "14", "-cl", "10"],
        decode=lambda b, i, o: ["/usr/bin/draco_decoder", "-i", i, "-o", o]),
    "OpenMesh .pm (mkbalancedpm)": dict(
        tool="/usr/bin/OpenMesh-mkbalancedpm", ext=".pm",
        encode=lambda b, off, ply, o: ["/usr/bin/OpenMesh-mkbalancedpm", "-o", o, off],
        decode=None),
}

TIMEOUT = 1800


def log(*a):
    print(*a, file=sys.stderr, flush=True)


def tool_path(build, tool):
    return Path(tool) if tool.startswith("/") else build / tool


def is_available(build, tool, cache={}):
    """A tool is usable when it exists and is not a placeholder (they print "not implemented"
    and exit 2 whatever the arguments)."""
    path = tool_path(build, tool)
    if path in cache:
        return cache[path]
    ok = path.exists() and os.access(path, os.X_OK)
    if ok:
        p = subprocess.run([str(path)], capture_output=True, text=True, timeout=60)
        ok = "not implemented" not in (p.stdout + p.stderr)
    cache[path] = ok
    return ok


def run_timed(argv, cwd=None):
    """Runs argv under /usr/bin/time; returns (wall seconds, peak RSS bytes, stdout, stderr, rc)."""
    argv = [str(a) for a in argv]
    with tempfile.NamedTemporaryFile("r", suffix=".time") as tf:
        t0 = time.perf_counter()
        p = subprocess.run(["/usr/bin/time", "-f", "%e %M", "-o", tf.name] + argv, capture_output=True,
                           text=True, timeout=TIMEOUT, cwd=cwd)
        wall = time.perf_counter() - t0
        fields = tf.read().split()
    rss = int(fields[-1]) * 1024 if len(fields) >= 2 and fields[-1].isdigit() else None
    return wall, rss, p.stdout, p.stderr, p.returncode


def algorithm_seconds(stdout):
    """In-process time of the algorithm alone, when the tool reports it: the harness programs
    print {"seconds": ...}; pmz-simplify ends its summary line with "N.NNN s"."""
    for line in stdout.splitlines():
        line = line.strip()
        if line.startswith("{"):
            try:
                return float(json.loads(line)["seconds"])
            except (ValueError, KeyError):
                pass
        m = re.search(r"([0-9]+\.[0-9]+) s$", line)
        if m:
            return float(m.group(1))
    return None


def repeat(argv, reps):
    """Runs reps times; medians of wall time, algorithm time and peak memory. Raises on failure."""
    walls, algos, rsss = [], [], []
    for _ in range(reps):
        wall, rss, out, err, rc = run_timed(argv)
        if rc != 0:
            raise RuntimeError(f"{' '.join(map(str, argv))}: exit {rc}: {(err or out).strip()[-400:]}")
        walls.append(wall)
        if rss:
            rsss.append(rss)
        a = algorithm_seconds(out)
        if a is not None:
            algos.append(a)
    med = lambda v: statistics.median(v) if v else None
    return dict(wall_s=med(walls), algo_s=med(algos), rss=med(rsss))


def compare(build, original, other, samples=None):
    argv = [build / "bin/pmz-compare", original, other, "--json"]
    if samples:
        argv += ["--samples", str(samples)]
    p = subprocess.run([str(a) for a in argv], capture_output=True, text=True, timeout=TIMEOUT)
    if p.returncode != 0:
        raise RuntimeError(f"pmz-compare {other}: {p.stderr.strip()}")
    return json.loads(p.stdout)


def off_counts(path):
    """Vertex and face counts from an OFF header (the corpus is OFF)."""
    with open(path, errors="replace") as f:
        tokens = []
        for line in f:
            line = line.split("#")[0].split()
            if not line:
                continue
            if not tokens and line[0].endswith("OFF"):
                line = line[1:]
            tokens += line
            if len(tokens) >= 2:
                return int(tokens[0]), int(tokens[1])
    raise RuntimeError(f"{path}: not an OFF file")


def write_icosphere(path, levels):
    """Small closed test mesh for the smoke run (no corpus needed)."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    norm = lambda p: tuple(c / math.sqrt(sum(x * x for x in p)) for c in p)
    v = [norm(p) for p in v]
    for _ in range(levels):
        mids, nf = {}, []

        def mid(a, b):
            k = (min(a, b), max(a, b))
            if k not in mids:
                # A bumpy sphere, so simplifiers have features to keep.
                p = norm(tuple((x + y) / 2 for x, y in zip(v[a], v[b])))
                r = 1 + 0.1 * math.sin(5 * p[0]) * math.sin(4 * p[1])
                v.append(tuple(c * r for c in p))
                mids[k] = len(v) - 1
            return mids[k]
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    with open(path, "w") as out:
        out.write(f"OFF\n{len(v)} {len(f)} 0\n")
        out.writelines(f"{x:.7g} {y:.7g} {z:.7g}\n" for x, y, z in v)
        out.writelines(f"3 {a} {b} {c}\n" for a, b, c in f)


def fmt(x, spec):
    return "–" if x is None else format(x, spec)


def run_simplifiers(args, build, meshes, out, rows):
    for name, path in meshes:
        nv, nf = off_counts(path)
        ratios = args.ratios or (BIG_RATIOS if name == BIG else RATIOS)
        for method in args.methods:
            spec = SIMPLIFIERS[method]
            if not all(is_available(build, t) for t in [spec["tool"]] + spec.get("needs", [])):
                continue
            work = out / "meshes" / name / method
            work.mkdir(parents=True, exist_ok=True)
            try:
                if "prepare" in spec:
                    subprocess.run([str(a) for a in spec["prepare"](build, path, work)], check=True,
                                   capture_output=True, timeout=TIMEOUT)
                for ratio in ratios:
                    faces = max(4, round(ratio * nf))
                    dst = work / f"{faces}.off"
                    t = repeat(spec["cmd"](build, path, dst, faces, work), args.reps)
                    err = compare(build, path, dst)
                    row = dict(kind="simplify", mesh=name, faces=nf, vertices=nv, method=method, ratio=ratio,
                               target=faces, faces_out=err["faces_other"], mean=err["mean"], max=err["max"],
                               rms=err["rms"], **t)
                    rows.append(row)
                    log(f"{name:20s} {method:20s} {ratio:5.2f} -> {row['faces_out']:8d} faces  "
                        f"mean {row['mean']:.3e} max {row['max']:.3e}  {fmt(t['algo_s'], '.3f')} s "
                        f"(process {t['wall_s']:.3f} s)")
            except (RuntimeError, subprocess.SubprocessError, OSError) as e:
                rows.append(dict(kind="failure", mesh=name, method=method, error=str(e)[:300]))
                log(f"{name:20s} {method:20s} FAILED: {e}")


def run_codecs(args, build, meshes, out, rows):
    for name, path in meshes:
        nv, nf = off_counts(path)
        work = out / "codecs" / name
        work.mkdir(parents=True, exist_ok=True)
        ply = work / "input.ply"
        for codec in args.codecs:
            spec = CODECS[codec]
            if not all(is_available(build, t) for t in [spec["tool"]] + spec.get("needs", [])):
                continue
            try:
                if not ply.exists():  # Draco reads PLY, not OFF; converted once, not timed
                    subprocess.run([str(build / "bench/bench-subdivide"), str(path), str(ply), "0"], check=True,
                                   capture_output=True, timeout=TIMEOUT)
                tag = re.sub(r"[^a-z0-9]+", "-", codec.lower()).strip("-")
                enc = work / (tag + spec["ext"])
                te = repeat(spec["encode"](build, path, ply, enc), args.reps)
                row = dict(kind="codec", mesh=name, faces=nf, vertices=nv, method=codec, bytes=enc.stat().st_size,
                           encode_s=te["wall_s"], encode_rss=te["rss"])
                if spec["decode"]:
                    dec = work / (tag + "-decoded.ply")
                    td = repeat(spec["decode"](build, enc, dec), args.reps)
                    err = compare(build, path, dec)
                    row.update(decode_s=td["wall_s"], decode_rss=td["rss"], mean=err["mean"], max=err["max"])
                rows.append(row)
                log(f"{name:20s} {codec:28s} {row['bytes']:9d} B  enc {row['encode_s']:.3f} s"
                    + (f"  dec {row['decode_s']:.3f} s  mean {row['mean']:.2e}" if "decode_s" in row else ""))
            except (RuntimeError, subprocess.SubprocessError, OSError) as e:
                rows.append(dict(kind="failure", mesh=name, method=codec, error=str(e)[:300]))
                log(f"{name:20s} {codec:28s} FAILED: {e}")


def stopped_above(r):
    """The method stopped above 1.1x the target face count (no legal collapse left)."""
    return r["faces_out"] > 1.1 * r["target"]


def summary_tables(sel, methods, meshes, ratio):
    """Mean and max error tables at one ratio: every method per mesh, then per column the median
    and worst ratio to the better of the peers on that mesh (meshes where every method stopped
    above the target left out; a mesh both sides simplify exactly counts 1)."""
    L = []
    peers = [m for m in PEERS if m in methods]
    for key, title in (("mean", "Mean error"), ("max", "Max (Hausdorff) error")):
        L.append(f"### {title} at {ratio:g} of the faces (×1e-4 of the diagonal)\n")
        head = "| mesh | faces | " + " | ".join(methods) + " |"
        L.append(head)
        L.append("|" + "---|" * (head.count("|") - 1))
        to_best = {m: [] for m in methods}
        for mesh in meshes:
            by = {r["method"]: r for r in sel if r["mesh"] == mesh}
            if not by:
                continue
            faces = next(iter(by.values()))["faces"]
            cells = [fmt(by[m][key] * 1e4 if m in by else None, ".3f") + ("*" if m in by and stopped_above(by[m]) else "")
                     for m in methods]
            L.append(f"| {mesh} | {faces} | " + " | ".join(cells) + " |")
            if not all(p in by for p in peers) or all(stopped_above(r) for r in by.values()):
                continue
            best = min(by[p][key] for p in peers) if peers else None
            for m in methods:
                if m in by and best is not None:
                    exact = 1e-10  # of the diagonal: both exact
                    to_best[m].append(1.0 if by[m][key] < exact and best < exact
                                      else by[m][key] / best if best > 0 else math.inf)
        if peers:
            for label, f in (("median / best peer", statistics.median), ("worst / best peer", max)):
                L.append(f"| {label} | | " + " | ".join(fmt(f(to_best[m]) if to_best[m] else None, ".3f")
                                                      for m in methods) + " |")
            n = max((len(v) for v in to_best.values()), default=0)
            L.append(f"\nRatios to the better of {' and '.join(peers)} on each mesh, over {n} meshes "
                     "(meshes where every method stopped above the target left out).  ")
        L.append("\\* stopped above 1.1× the target face count (no legal collapse left).\n")
    for a, b in [("pmz-guarded", "pmz-multifeature"), ("pmz-multifeature", "pmz-qem"),
                 ("pmz-prefix", "pmz-guarded"), ("pmz-prefix-lossless", "pmz-guarded")]:
        for key in ("mean", "max"):
            q = [by[a][key] / by[b][key] for by in
                 ({r["method"]: r for r in sel if r["mesh"] == mesh} for mesh in meshes)
                 if a in by and b in by and by[b][key] > 0]
            if q:
                L.append(f"Median {a} / {b} {key}-error ratio at {ratio:g}: {statistics.median(q):.3f} "
                         f"(max {max(q):.3f}) over {len(q)} meshes  ")
    L.append("")
    return L


def report(args, rows, out, command):
    simp = [r for r in rows if r["kind"] == "simplify"]
    codecs = [r for r in rows if r["kind"] == "codec"]
    fails = [r for r in rows if r["kind"] == "failure"]
    methods = [m for m in SIMPLIFIERS if any(r["method"] == m for r in simp)]
    meshes = list(dict.fromkeys(r["mesh"] for r in simp + codecs))
    L = []
    L.append(f"Command: `{command}`  ")
    L.append(f"Machine: {os.cpu_count()} cores, {time.strftime('%Y-%m-%d %H:%M')}; timings are medians of "
             f"{args.reps} run(s). Errors: symmetric Hausdorff distance by `pmz-compare` (Metro-style, "
             "relative to the original's bounding-box diagonal; mean = average of both directions' "
             "area-weighted means, max = Hausdorff distance).\n")
    skipped = [m for m in args.methods if m not in methods] + [c for c in args.codecs
                                                                 if not any(r["method"] == c for r in codecs)]
    if skipped:
        L.append("Not run (tool missing or still a placeholder): " + ", ".join(f"`{s}`" for s in skipped) + "\n")

    for ratio in SUMMARY_RATIOS:
        sel = [r for r in simp if abs(r["ratio"] - ratio) < 1e-9]
        if sel:
            L.extend(summary_tables(sel, methods, meshes, ratio))

    big = [r for r in simp if r["mesh"] == BIG]
    if big:
        L.append(f"### Speed and memory on {BIG} ({big[0]['faces']} faces)\n")
        L.append("| method | ratio | faces out | time (s) | process (s) | peak RSS (MB) | bytes / input face |")
        L.append("|---|---|---|---|---|---|---|")
        for r in big:
            L.append(f"| {r['method']} | {r['ratio']:g} | {r['faces_out']} | {fmt(r['algo_s'], '.3f')} | "
                     f"{r['wall_s']:.3f} | {fmt(r['rss'] / 2**20 if r['rss'] else None, '.1f')} | "
                     f"{fmt(r['rss'] / r['faces'] if r['rss'] else None, '.0f')} |")
        L.append("")

    if simp:
        L.append("### Simplification: all runs\n")
        L.append("time = the algorithm alone as the tool reports it (no file I/O); process = whole process "
                 "wall time (read + simplify + write); peak RSS of the process.\n")
        L.append("| mesh | faces | method | ratio | faces out | mean | max | time (s) | process (s) | peak RSS (MB) |")
        L.append("|---|---|---|---|---|---|---|---|---|---|")
        for r in simp:
            L.append(f"| {r['mesh']} | {r['faces']} | {r['method']} | {r['ratio']:g} | {r['faces_out']} | "
                     f"{r['mean']:.3e} | {r['max']:.3e} | {fmt(r['algo_s'], '.3f')} | {r['wall_s']:.3f} | "
                     f"{fmt(r['rss'] / 2**20 if r['rss'] else None, '.1f')} |")
        L.append("")
    if codecs:
        L.append("### Full-resolution codecs\n")
        L.append("Encode/decode: whole-process wall time (decode writes PLY). Error: decoded vs original.\n")
        L.append("| mesh | faces | codec | bytes | bits/vertex | encode (s) | decode (s) | peak RSS enc/dec (MB) "
                 "| mean | max |")
        L.append("|---|---|---|---|---|---|---|---|---|---|")
        for r in codecs:
            rss = f"{fmt(r['encode_rss'] / 2**20 if r['encode_rss'] else None, '.1f')} / " + \
                  fmt(r['decode_rss'] / 2**20 if r.get('decode_rss') else None, '.1f')
            L.append(f"| {r['mesh']} | {r['faces']} | {r['method']} | {r['bytes']} | "
                     f"{8 * r['bytes'] / r['vertices']:.2f} | {r['encode_s']:.3f} | {fmt(r.get('decode_s'), '.3f')} | "
                     f"{rss} | {fmt(r.get('mean'), '.3e')} | {fmt(r.get('max'), '.3e')} |")
        L.append("")
        by_mesh = {}
        for r in codecs:
            by_mesh.setdefault(r["mesh"], {})[r["method"]] = r["bytes"]
        for a, b in [("pmz (14 bits)", "draco -qp 14 -cl 10"), ("pmz level 1 (14 bits)", "draco -qp 14 -cl 10"),
                     ("pmz (14 bits)", "OpenMesh .pm (mkbalancedpm)")]:
            q = [m[a] / m[b] for m in by_mesh.values() if a in m and b in m]
            if q:
                L.append(f"Median size {a} / {b}: {statistics.median(q):.3f} over {len(q)} meshes  ")
        L.append("")
    if fails:
        L.append("### Failures\n")
        L.extend(f"- {r['mesh']} / {r['method']}: `{r['error']}`" for r in fails)
        L.append("")
    (out / "RESULTS.md").write_text("\n".join(L) + "\n")
    return simp


def plot(simp, out):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        log("python3-matplotlib missing: no plots")
        return []
    meshes = list(dict.fromkeys(r["mesh"] for r in simp))
    methods = list(dict.fromkeys(r["method"] for r in simp))
    files = []
    for key in ("mean", "max"):
        cols = min(4, len(meshes))
        rows_n = math.ceil(len(meshes) / cols)
        fig, axes = plt.subplots(rows_n, cols, figsize=(4 * cols, 3.2 * rows_n), squeeze=False)
        for ax, mesh in zip(axes.flat, meshes):
            for m in methods:
                pts = sorted((r["faces_out"] / r["faces"], r[key]) for r in simp if r["mesh"] == mesh and r["method"] == m)
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", ms=3, label=m)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_title(mesh, fontsize=9)
            ax.grid(True, which="both", alpha=0.3)
            ax.tick_params(labelsize=7)
        for ax in list(axes.flat)[len(meshes):]:
            ax.axis("off")
        axes.flat[0].legend(fontsize=7)
        fig.supxlabel("face ratio (output / input)")
        fig.supylabel(f"{key} symmetric Hausdorff / bbox diagonal")
        fig.tight_layout()
        path = out / f"error_{key}.png"
        fig.savefig(path, dpi=90)
        plt.close(fig)
        files.append(path)
    return files


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--build", default=str(ROOT / "build"), help="build directory with bin/ and bench/")
    ap.add_argument("--corpus", default=os.environ.get("PMZ_CORPUS", str(ROOT / "corpus")))
    ap.add_argument("--out", default=str(ROOT / "bench-out"))
    ap.add_argument("--quick", action="store_true", help="3 meshes, 2 ratios, 1 repetition, no 1M mesh")
    ap.add_argument("--smoke", action="store_true", help="one generated tiny mesh (ctest)")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--meshes", help="comma-separated corpus names")
    ap.add_argument("--ratios", help="comma-separated face ratios")
    ap.add_argument("--methods", default=",".join(SIMPLIFIERS))
    ap.add_argument("--codecs", default=",".join(CODECS))
    ap.add_argument("--no-big", action="store_true", help=f"skip {BIG}")
    ap.add_argument("--report-only", action="store_true", help="re-render out/results.json (no runs)")
    args = ap.parse_args()
    build, out = Path(args.build).resolve(), Path(args.out).resolve()
    args.methods = [m for m in args.methods.split(",") if m]
    args.codecs = [c for c in args.codecs.split(",") if c]
    for m in args.methods:
        if m not in SIMPLIFIERS:
            ap.error(f"unknown method {m}; known: {', '.join(SIMPLIFIERS)}")
    for c in args.codecs:
        if c not in CODECS:
            ap.error(f"unknown codec {c}; known: {', '.join(CODECS)}")
    args.ratios = [float(x) for x in args.ratios.split(",")] if args.ratios else None
    if not is_available(build, "bin/pmz-compare"):
        sys.exit(f"bench: {build}/bin/pmz-compare missing or a placeholder")
    out.mkdir(parents=True, exist_ok=True)

    corpus = Path(args.corpus)
    if args.smoke:
        args.reps, args.ratios = 1, [0.1]
        tiny = out / "tiny-icosphere.off"
        write_icosphere(tiny, 4)  # 5120 faces
        meshes = [("tiny-icosphere", tiny)]
    else:
        names = args.meshes.split(",") if args.meshes else (QUICK if args.quick else CORPUS + ([] if args.no_big else [BIG]))
        if args.quick:
            args.reps, args.ratios = 1, args.ratios or SUMMARY_RATIOS
        meshes = []
        for n in names:
            p = corpus / f"{n}.off"
            if p.exists():
                meshes.append((n, p))
            else:
                log(f"bench: {p} missing (run scripts/fetch_corpus.sh); skipped")
        if not meshes:
            sys.exit("bench: no corpus meshes; run scripts/fetch_corpus.sh first")

    command = " ".join(["python3", "tests/bench/bench.py"] + sys.argv[1:])
    if args.report_only:  # re-render the last run's tables and plots
        rows = json.loads((out / "results.json").read_text())
        command = (out / "command.txt").read_text().strip() if (out / "command.txt").exists() else command
    else:
        rows = []
        run_simplifiers(args, build, meshes, out, rows)
        run_codecs(args, build, meshes, out, rows)
        (out / "results.json").write_text(json.dumps(rows, indent=1))
        (out / "command.txt").write_text(command + "\n")
    simp = report(args, rows, out, command)
    plots = plot(simp, out) if simp else []
    log(f"bench: wrote {out / 'RESULTS.md'}, {out / 'results.json'}" + "".join(f", {p}" for p in plots))
    fails = [r for r in rows if r["kind"] == "failure"]
    if args.smoke:
        # The smoke test fails on any failed run and on implausible results.
        bad = [r for r in rows if r["kind"] == "simplify" and not (0 <= r["mean"] <= r["max"] < 0.5
                                                                    and r["faces_out"] <= 2 * r["target"])]
        if fails or bad or not rows:
            log(f"bench smoke: {len(fails)} failed runs, {len(bad)} implausible rows, {len(rows)} rows")
            sys.exit(1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
