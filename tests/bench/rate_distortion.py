#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Streaming rate-distortion: bytes a client needs to reach an error, pmz against a Draco LOD chain.

The chain is what a Draco user streams progressively: pmz-simplify's meshes at 1% and 10% of the
faces, then the original, each `draco_encoder -qp 14 -cl 10`, fetched one after the other. Its
three members' mean errors (pmz-compare against the original, decoded by draco_decoder) span the
range; LEVELS error levels are spaced logarithmically from the coarsest member's error to the
finest's. For each level:
  - the chain needs the bytes of every member up to the first whose error is at most the level;
  - pmz needs the shortest prefix of its stream (pmz-encode's defaults) whose finest level
    (pmz-decode --bytes N) has a mean error at most the level: the first prefix of a geometric
    grid that reaches it, then bisection between it and the grid point before (the error of a
    prefix falls with its length, but not strictly: bisection finds a prefix that reaches the
    level, not always the shortest).
A level counts as reached within 1% (pmz-compare's sampling noise): the finest level is the
original at 14 bits, which pmz and Draco quantise on different grids.
The ratio pmz / chain per level; per mesh their geometric mean and largest. Errors and sizes
do not depend on the machine's load.

Usage: python3 tests/bench/rate_distortion.py [--build build] [--out bench-out/rd]
           [--levels 13] MESH [MESH ...]
Writes OUT/rate_distortion.json and prints one table row per mesh.
"""
import argparse
import json
import math
import statistics
import subprocess
import sys
from pathlib import Path

DRACO = ["-qp", "14", "-cl", "10"]
LOD_RATIOS = [0.01, 0.1]
GRID_POINTS = 24   # prefixes on the geometric grid, before bisection
BISECT_STEPS = 7
TOLERANCE = 0.01


def run(argv):
    p = subprocess.run([str(a) for a in argv], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, argv))}: exit {p.returncode}: "
                           f"{(p.stderr or p.stdout).strip()[-300:]}")
    return p.stdout


class Mesh:
    def __init__(self, build, original, work):
        self.build, self.original, self.work = build, original, work
        self.errors = {}  # prefix bytes -> mean error

    def compare(self, other):
        out = run([self.build / "bin/pmz-compare", self.original, other, "--json"])
        return json.loads(out)["mean"]

    def chain(self):
        """[(cumulative bytes, mean error)] of the Draco LOD chain, coarse to fine."""
        members, total = [], 0
        for ratio in LOD_RATIOS + [None]:
            tag = f"lod{ratio}" if ratio else "full"
            ply = self.work / f"{tag}.ply"
            if ratio:
                run([self.build / "bin/pmz-simplify", self.original, "--ratio", ratio, "-o", ply,
                     "-q"])
            else:  # the original as PLY: draco_encoder reads PLY and OBJ
                run([self.build / "bin/pmz-simplify", self.original, "--ratio", 1, "-o", ply,
                     "-q"])
            drc, decoded = self.work / f"{tag}.drc", self.work / f"{tag}.drc.ply"
            run(["draco_encoder", "-i", ply, "-o", drc] + DRACO)
            run(["draco_decoder", "-i", drc, "-o", decoded])
            total += drc.stat().st_size
            members.append((total, self.compare(decoded)))
        return members

    def prefix_error(self, n):
        if n not in self.errors:
            out = self.work / "prefix.ply"
            p = subprocess.run([str(a) for a in (self.build / "bin/pmz-decode", self.stream,
                                                 "--bytes", n, "-o", out)], capture_output=True)
            # A prefix without the whole base mesh shows nothing.
            self.errors[n] = self.compare(out) if p.returncode == 0 else math.inf
        return self.errors[n]

    def pmz_bytes(self, level, grid):
        """A prefix reaching `level` (None when even the whole stream does not)."""
        before = 0
        for n in grid:
            if self.prefix_error(n) <= level:
                lo, hi = before, n  # lo does not reach the level (or is 0), hi does
                for _ in range(BISECT_STEPS):
                    if hi - lo <= max(16, hi // 200):
                        break
                    mid = (lo + hi) // 2
                    if self.prefix_error(mid) <= level:
                        hi = mid
                    else:
                        lo = mid
                return hi
            before = n
        return None

    def measure(self, levels):
        self.work.mkdir(parents=True, exist_ok=True)
        self.stream = self.work / "mesh.pmz"
        run([self.build / "bin/pmz-encode", self.original, "-o", self.stream])
        size = self.stream.stat().st_size
        chain = self.chain()
        coarse, fine = chain[0][1], chain[-1][1]
        grid = sorted({max(64, round(size * (64 / size) ** (1 - i / (GRID_POINTS - 1))))
                       for i in range(GRID_POINTS)} | {size})
        rows = []
        for i in range(levels):
            level = coarse * (fine / coarse) ** (i / (levels - 1)) if levels > 1 else coarse
            # A level is reached within pmz-compare's sampling noise (its own members' errors
            # reach theirs): both ends are the same mesh at 14 bits, quantised on different grids.
            level *= 1 + TOLERANCE
            chain_bytes = next(b for b, e in chain if e <= level)
            pmz = self.pmz_bytes(level, grid)
            rows.append({"error": level, "chain": chain_bytes, "pmz": pmz,
                         "ratio": pmz / chain_bytes if pmz else None})
        ratios = [r["ratio"] for r in rows]
        reached = [r for r in ratios if r is not None]
        return {"mesh": str(self.original), "pmz_size": size, "chain": chain,
                "pmz_full_error": self.prefix_error(size), "levels": rows,
                "geomean": math.exp(statistics.fmean(map(math.log, reached))) if reached else None,
                "max": max(reached) if reached else None,
                "unreached": len(ratios) - len(reached)}


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default="bench-out/rd")
    ap.add_argument("--levels", type=int, default=13)
    args = ap.parse_args()
    build, out = Path(args.build).resolve(), Path(args.out)
    results = []
    print("| mesh | pmz bytes | chain bytes (1% / 10% / full) | geometric mean | largest "
          "| levels not reached |")
    print("|---|---|---|---|---|---|")
    for path in args.meshes:
        name = Path(path).stem
        r = Mesh(build, Path(path).resolve(), out / name).measure(args.levels)
        results.append(r)
        chain = " / ".join(f"{b:,}" for b, _ in r["chain"])
        gm = f"{r['geomean']:.3f}" if r["geomean"] else "-"
        mx = f"{r['max']:.3f}" if r["max"] else "-"
        print(f"| {name} | {r['pmz_size']:,} | {chain} | {gm} | {mx} | {r['unreached']} |",
              flush=True)
        (out / "rate_distortion.json").write_text(json.dumps(results, indent=1))
    gms = [r["geomean"] for r in results if r["geomean"]]
    if gms:
        print(f"median geometric mean {statistics.median(gms):.3f}, "
              f"largest ratio {max(r['max'] for r in results if r['max']):.3f}")


if __name__ == "__main__":
    sys.exit(main())
