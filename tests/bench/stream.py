#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Streaming benchmark: when does a client on a link of R Mbit/s see a good mesh?

For each mesh and link rate, the time (transfer and decoding overlapped, as a streaming client
overlaps them) until the mean error first drops below 1e-3 and 1e-4 of the bounding-box
diagonal, and until full resolution, for
  - pmz at each level (the default, and "pmz speed": pmz-encode --level 1, the same meshes at
    every face count, so the same errors): bench-stream feeds the decoder library 4096-byte slices as they arrive
    at the link rate and refines everything that has arrived after each, on a virtual clock
    (max(arrival, clock) + measured decode time);
  - Draco single-rate (-qp 14 -cl 10): the whole file arrives, then draco_decoder decodes it;
  - a Draco LOD chain: pmz-simplify's meshes at 1% and 10% of the faces and the full mesh, each
    Draco-coded the same way, sent coarse to fine; each level is decoded once it has arrived and
    the level before is decoded.
Decode times are CPU time (bench-stream: the process's, per feed + refine; Draco: user + sys of
the draco_decoder process less that of its start without work, so its PLY writing is still in
it), medians of --reps runs:
on a shared machine CPU time is what other processes inflate least. Errors are pmz-compare means
of the levels reached: for pmz, of pmz-decode --faces F on a grid of face counts (the time to a
threshold is the time to the first grid level below it, so slightly late by the grid's spacing).

Usage: python3 tests/bench/stream.py [--build build] [--out bench-out/stream]
           [--meshes bunny00-loop2,armadillo,bunny00] [--links 2,10,100] [--reps 3]
Writes OUT/stream.json, OUT/STREAM.md (the table) and OUT/stream.png.
"""
import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
from pathlib import Path

GRID = [0.002, 0.005, 0.01, 0.02, 0.03, 0.05, 0.07, 0.1, 0.15, 0.2, 0.3, 0.5, 0.7, 1.0]
THRESHOLDS = [1e-3, 1e-4]
LOD_RATIOS = [0.01, 0.1]
SLICE = 4096
DRACO = ["-qp", "14", "-cl", "10"]


def log(*a):
    print(*a, file=sys.stderr, flush=True)


def run(argv, **kw):
    p = subprocess.run([str(a) for a in argv], capture_output=True, text=True, **kw)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, argv))}: exit {p.returncode}: {(p.stderr or p.stdout).strip()[-300:]}")
    return p.stdout


def child_cpu(argv, check=True):
    """user + sys CPU seconds of one run of argv."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    if check:
        run(argv)
    else:
        subprocess.run([str(a) for a in argv], capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def mean_error(build, original, other):
    """pmz-compare's mean, cached in OTHER's folder (errors.json, by file name): a re-run with
    --reps or --links changed only re-times."""
    cache_path = Path(other).parent / "errors.json"
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    if Path(other).name not in cache:
        out = run([build / "bin/pmz-compare", original, other, "--json", "--samples", "500000"])
        cache[Path(other).name] = json.loads(out)["mean"]
        cache_path.write_text(json.dumps(cache, indent=1))
    return cache[Path(other).name]


def cached_error(other):
    cache_path = Path(other).parent / "errors.json"
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    return cache.get(Path(other).name)


def off_faces(path):
    with open(path) as f:
        words = []
        for line in f:
            line = line.split("#")[0].split()
            words += line
            if len(words) >= 3:
                break
    return int(words[2])


def measure_mesh(args, build, name, off, work):
    work.mkdir(parents=True, exist_ok=True)
    full_faces = off_faces(off)
    pmz = work / f"{name}.pmz"
    if not pmz.exists():
        run([build / "bin/pmz-encode", off, "-o", pmz])
    pmz_speed = work / f"{name}-l1.pmz"
    if not pmz_speed.exists():
        run([build / "bin/pmz-encode", off, "-o", pmz_speed, "--level", "1"])
    ply = work / f"{name}.ply"
    if not ply.exists():  # Draco reads PLY, not OFF
        run([build / "bench/bench-subdivide", off, ply, "0"])
    # Draco files: the LOD chain's coarse levels, then the full mesh (= the single-rate file).
    # draco_decoder's process start (loading libdraco; its usage message without arguments) is
    # subtracted: bench-stream times the pmz library in-process.
    start = statistics.median(child_cpu(["/usr/bin/draco_decoder"], check=False) for _ in range(5))
    levels = []
    for r in LOD_RATIOS + [1.0]:
        src = ply if r == 1.0 else work / f"{name}-{r:g}.ply"
        if r != 1.0 and not src.exists():
            run([build / "bin/pmz-simplify", off, "-o", src, "--ratio", str(r)])
        drc = work / f"{name}-{r:g}.drc"
        if not drc.exists():
            run(["/usr/bin/draco_encoder", "-i", src, "-o", drc] + DRACO)
        dec = work / f"{name}-{r:g}-draco.ply"
        cpu = statistics.median(child_cpu(["/usr/bin/draco_decoder", "-i", drc, "-o", dec])
                                for _ in range(args.reps))
        levels.append(dict(ratio=r, bytes=drc.stat().st_size, decode_s=max(0.0, cpu - start), process_s=cpu,
                           mean=mean_error(build, off, dec)))
        log(f"{name}: draco {r:g}: {levels[-1]}")
    # pmz levels on the grid of face counts.
    grid = []
    for g in GRID:
        faces = max(1, round(g * full_faces))
        dec = work / f"{name}-pmz-{g:g}.ply"
        if cached_error(dec) is None:
            run([build / "bin/pmz-decode", pmz, "-o", dec, "--faces", faces])
        grid.append(dict(fraction=g, faces=faces, mean=mean_error(build, off, dec)))
        dec.unlink(missing_ok=True)
        log(f"{name}: pmz {g:g}: {grid[-1]}")
    links = {}
    for mbit in args.links:
        for key, stream in (("", pmz), ("speed ", pmz_speed)):  # the levels alternate
            runs = []
            for _ in range(args.reps):
                out = run([build / "bench/bench-stream", stream, "--slice", SLICE, "--refine", "all",
                           "--mbit", mbit, "--faces", ",".join(str(x["faces"]) for x in grid)])
                runs.append(json.loads(out))
            reached = {}
            for f in [x["faces"] for x in grid]:
                reached[f] = statistics.median(dict((a, b) for a, b in r["reached"])[f] for r in runs)
            links[key + str(mbit)] = dict(
                reached=reached, complete_s=statistics.median(r["complete_s"] for r in runs),
                decode_cpu_s=statistics.median(r["cpu_s"] for r in runs))
            log(f"{name}: pmz {key}at {mbit} Mbit/s: complete {links[key + str(mbit)]['complete_s']:.3f} s")
    return dict(mesh=name, faces=full_faces, pmz_bytes=pmz.stat().st_size,
                pmz_speed_bytes=pmz_speed.stat().st_size, draco=levels, pmz_grid=grid,
                pmz_links={k: v for k, v in links.items() if not k.startswith("speed ")},
                pmz_speed_links={k[6:]: v for k, v in links.items() if k.startswith("speed ")})


def times(m, mbit):
    """Per method: {thr: seconds or None, 'full': seconds}."""
    rate = mbit * 1e6 / 8
    res = {}
    # pmz, each level: the first grid level below each threshold.
    for meth, key in (("pmz", "pmz_links"), ("pmz speed", "pmz_speed_links")):
        if key not in m:  # (a stream.json from before the speed level)
            continue
        link = m[key][str(mbit)]
        row = {"full": link["complete_s"]}
        for thr in THRESHOLDS:
            hit = next((g for g in m["pmz_grid"] if g["mean"] < thr), None)
            row[thr] = link["reached"][hit["faces"]] if hit else None
        res[meth] = row
    # Draco single-rate: the full file, then its decode.
    full = m["draco"][-1]
    t = full["bytes"] / rate + full["decode_s"]
    res["draco"] = {"full": t, **{thr: (t if full["mean"] < thr else None) for thr in THRESHOLDS}}
    # Draco LOD chain: coarse to fine, each decoded after it arrived and after the one before.
    done, arrived, chain = 0.0, 0, []
    for lv in m["draco"]:
        arrived += lv["bytes"]
        done = max(done, arrived / rate) + lv["decode_s"]
        chain.append((done, lv["mean"]))
    res["draco LOD"] = {"full": chain[-1][0],
                        **{thr: next((d for d, e in chain if e < thr), None) for thr in THRESHOLDS}}
    return res


def fmt(t):
    return "never" if t is None else f"{t:.2f}"


def report(results, links, out):
    lines = ["| mesh (faces, pmz / Draco bytes) | link | method | < 1e-3 | < 1e-4 | full |", "|---|---|---|---|---|---|"]
    verdicts = []
    for m in results:
        speed = f" ({m['pmz_speed_bytes']:,} speed)" if "pmz_speed_bytes" in m else ""
        label = f"{m['mesh']} ({m['faces']:,}, {m['pmz_bytes']:,}{speed} / {m['draco'][-1]['bytes']:,})"
        for mbit in links:
            t = times(m, mbit)
            for meth in [x for x in ["pmz", "pmz speed", "draco", "draco LOD"] if x in t]:
                r = t[meth]
                cells = []
                for key in THRESHOLDS + ["full"]:
                    best = min((t[x][key] for x in t if t[x][key] is not None), default=None)
                    s = fmt(r[key])
                    cells.append(f"**{s}**" if r[key] is not None and r[key] == best else s)
                lines.append(f"| {label} | {mbit:g} Mbit/s | {meth} | " + " | ".join(cells) + " |")
            for key, what in [(1e-3, "mean error < 1e-3"), (1e-4, "< 1e-4"), ("full", "full resolution")]:
                others = [t[x][key] for x in ["draco", "draco LOD"]]
                for meth in [x for x in ["pmz", "pmz speed"] if x in t]:
                    p = t[meth][key]
                    if p is None:
                        v = f"{meth} never gets there"
                    elif all(o is None or p < o for o in others):
                        v = f"{meth} ahead of both"
                    elif all(o is not None and p > o for o in others):
                        v = f"{meth} behind both"
                    else:
                        v = f"{meth} between the two"
                    verdicts.append(f"- {m['mesh']}, {mbit:g} Mbit/s, {what}: {v} "
                                    f"({meth} {fmt(p)} s, Draco {fmt(others[0])} s, LOD chain {fmt(others[1])} s)")
    return "\n".join(lines) + "\n\n" + "\n".join(verdicts) + "\n"


def plot(results, links, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        log("stream: no matplotlib, no plot")
        return False
    keys = [(1e-3, "mean error < 1e-3"), (1e-4, "mean error < 1e-4"), ("full", "full resolution")]
    fig, axes = plt.subplots(len(results), 3, figsize=(12, 3.2 * len(results)), squeeze=False)
    for i, m in enumerate(results):
        for j, (key, title) in enumerate(keys):
            ax = axes[i][j]
            for meth, style in [("pmz", "o-"), ("pmz speed", "D-"), ("draco", "s--"), ("draco LOD", "^:")]:
                if meth not in times(m, links[0]):
                    continue
                xs, ys = [], []
                for mbit in links:
                    v = times(m, mbit)[meth][key]
                    if v is not None:
                        xs.append(mbit)
                        ys.append(v)
                ax.plot(xs, ys, style, label=meth)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xticks(links)
            ax.set_xticklabels([f"{x:g}" for x in links])
            ax.set_title(f"{m['mesh']}: {title}", fontsize=9)
            ax.set_xlabel("link, Mbit/s")
            ax.set_ylabel("seconds")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default="bench-out/stream")
    ap.add_argument("--corpus", default="corpus")
    ap.add_argument("--meshes", default="bunny00-loop2,armadillo,bunny00")
    ap.add_argument("--links", default="2,10,100")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--report-only", action="store_true", help="re-render OUT/stream.json")
    args = ap.parse_args()
    build, out = Path(args.build).resolve(), Path(args.out)
    args.links = [float(x) for x in args.links.split(",")]
    out.mkdir(parents=True, exist_ok=True)
    if args.report_only:
        results = json.loads((out / "stream.json").read_text())
    else:
        results = []
        for name in args.meshes.split(","):
            off = Path(args.corpus) / f"{name}.off"
            if not off.exists():
                log(f"stream: {off} missing, skipped")
                continue
            results.append(measure_mesh(args, build, name, off.resolve(), out / name))
            (out / "stream.json").write_text(json.dumps(results, indent=1))
    # JSON turns the face-count keys into strings.
    for m in results:
        for link in list(m["pmz_links"].values()) + list(m.get("pmz_speed_links", {}).values()):
            link["reached"] = {int(k): v for k, v in link["reached"].items()}
    (out / "STREAM.md").write_text(report(results, args.links, out))
    plotted = plot(results, args.links, out / "stream.png")
    log(f"stream: wrote {out / 'STREAM.md'}, {out / 'stream.json'}" + (f", {out / 'stream.png'}" if plotted else ""))


if __name__ == "__main__":
    main()
