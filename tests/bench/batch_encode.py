#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Batch encoding against sequential runs (target: 8 assets with -j 2 in at most 0.6x the
time of 8 sequential runs, docs/benchmarks.md).

Side by side, alternating which goes first in each round: one `pmz-encode A B ... --out-dir D
-j JOBS` against one `pmz-encode X -o D/X.pmz` per asset, one after the other. Prints each
round's wall times, the medians and their ratio; checks the batch wrote the same bytes.

usage: batch_encode.py [--bin build/bin] [--corpus corpus] [--rounds 5] [--jobs 2] [MESH ...]
Default meshes: eight corpus meshes of 5k-70k faces."""
import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

DEFAULT = ["armadillo.off", "blade.off", "camel.off", "cheese.off", "fandisk.off",
           "lion-head.off", "man.off", "mannequin-devil.off"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default="build/bin")
    ap.add_argument("--corpus", default="corpus")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("meshes", nargs="*")
    a = ap.parse_args()
    meshes = a.meshes or [os.path.join(a.corpus, m) for m in DEFAULT]
    missing = [m for m in meshes if not os.path.exists(m)]
    if missing:
        print(f"batch_encode: missing meshes: {missing} (bash scripts/fetch_corpus.sh build)",
              file=sys.stderr)
        return 1
    enc = os.path.join(a.bin, "pmz-encode")
    work = tempfile.mkdtemp(prefix="pmz-batch-bench.")
    seq_dir, batch_dir = os.path.join(work, "seq"), os.path.join(work, "batch")

    def sequential():
        shutil.rmtree(seq_dir, ignore_errors=True)
        os.makedirs(seq_dir)
        t0 = time.perf_counter()
        for m in meshes:
            out = os.path.join(seq_dir, os.path.splitext(os.path.basename(m))[0] + ".pmz")
            subprocess.run([enc, m, "-o", out], check=True, stdout=subprocess.DEVNULL)
        return time.perf_counter() - t0

    def batch():
        shutil.rmtree(batch_dir, ignore_errors=True)
        os.makedirs(batch_dir)
        t0 = time.perf_counter()
        subprocess.run([enc] + meshes + ["--out-dir", batch_dir, "-j", str(a.jobs)], check=True,
                       stdout=subprocess.DEVNULL)
        return time.perf_counter() - t0

    seq_t, batch_t = [], []
    print(f"{len(meshes)} meshes, -j {a.jobs}, {a.rounds} rounds, {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.2f}")
    for r in range(a.rounds):
        order = [("sequential", sequential, seq_t), ("batch", batch, batch_t)]
        if r % 2:
            order.reverse()
        for name, f, times in order:
            times.append(f())
        print(f"round {r + 1}: sequential {seq_t[-1]:.3f} s, batch {batch_t[-1]:.3f} s, "
              f"ratio {batch_t[-1] / seq_t[-1]:.3f}")
    for f in sorted(os.listdir(seq_dir)):
        if open(os.path.join(seq_dir, f), "rb").read() != open(os.path.join(batch_dir, f),
                                                               "rb").read():
            print(f"batch_encode: {f} differs between batch and sequential", file=sys.stderr)
            return 1
    ms, mb = statistics.median(seq_t), statistics.median(batch_t)
    print(f"median: sequential {ms:.3f} s, batch -j {a.jobs} {mb:.3f} s, ratio {mb / ms:.3f} "
          f"(target <= 0.6); outputs identical")
    shutil.rmtree(work)
    return 0


if __name__ == "__main__":
    sys.exit(main())
