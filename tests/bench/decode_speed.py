#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Decode speed, side by side: pmz-decode against draco_decoder (PLY out), with the default
threads (the machine's cores) and with --threads 1 ("decode-1t"), the streaming pattern
(bench-stream: 997-byte feeds, refine(5000) after each) and the refinement rates of pmz-info
--decode (first, and again after coarsening).

Each round runs every program once (with --baseline, which tree goes first alternates), so a
shared machine's load hits them alike. bench-stream's figure is its decoder's CPU time from the
first feed to the last split (the file already read). Prints each round with the load average,
then the medians as one JSON line. --baseline DIR: another tree's build directory, whose
pmz-decode, bench-stream and pmz-info run in the same rounds (before/after comparisons).
--speed-pmz FILE: the same mesh encoded at the speed level (pmz-encode --level 1), run by the
--build tools in the same rounds as "speed". Targets: pmz-decode at most 1.0x draco_decoder's
elapsed time, at most 1.8x with --threads 1.

  python3 tests/bench/decode_speed.py --build build --pmz bunny00-loop2.pmz \\
      --drc bunny00-loop2.drc [--speed-pmz bunny00-loop2-l1.pmz] [--baseline ../main/build]
      [--rounds 7]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time


def load():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def child_cpu(cmd):
    """Elapsed and CPU (user + sys) seconds of one run of cmd; its output is discarded."""
    before = os.times()
    t0 = time.monotonic()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    elapsed = time.monotonic() - t0
    after = os.times()
    cpu = (after.children_user - before.children_user) + (after.children_system -
                                                          before.children_system)
    return elapsed, cpu


def tools(build):
    return dict(decode=os.path.join(build, "bin", "pmz-decode"),
                info=os.path.join(build, "bin", "pmz-info"),
                stream=os.path.join(build, "bench", "bench-stream"))


def round_of(name, t, pmz, out):
    r = {}
    r[name + " decode"] = child_cpu([t["decode"], pmz, "-o", out])
    r[name + " decode-1t"] = child_cpu([t["decode"], pmz, "-o", out, "--threads", "1"])
    s = subprocess.run([t["stream"], pmz, "--slice", "997", "--refine", "5000"], check=True,
                       capture_output=True, text=True).stdout
    j = json.loads(s)
    r[name + " stream"] = (j["wall_s"], j["cpu_s"], j["splits"])
    s = subprocess.run([t["info"], pmz, "--decode", "--json"], check=True, capture_output=True,
                       text=True).stdout
    j = json.loads(s)
    r[name + " info"] = (j["refine_cpu_ms"], j["rerefine_cpu_ms"])
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--baseline", help="another build directory, run in the same rounds")
    ap.add_argument("--pmz", required=True)
    ap.add_argument("--drc", required=True, help="the same mesh, draco_encoder -qp 14 -cl 10")
    ap.add_argument("--speed-pmz", help="the same mesh at pmz-encode --level 1")
    ap.add_argument("--rounds", type=int, default=7)
    a = ap.parse_args()
    sides = ([("new", tools(a.build), a.pmz)] +
             ([("base", tools(a.baseline), a.pmz)] if a.baseline else []) +
             ([("speed", tools(a.build), a.speed_pmz)] if a.speed_pmz else []))
    rounds = []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.ply")
        for i in range(a.rounds):
            r = {"load": load()}
            for name, t, pmz in (sides if i % 2 == 0 else sides[::-1]):  # who goes first alternates
                r.update(round_of(name, t, pmz, out))
            r["draco decode"] = child_cpu(["/usr/bin/draco_decoder", "-i", a.drc, "-o", out])
            rounds.append(r)
            print(f"round {i + 1}: load {r['load']:.2f}  " + "  ".join(
                f"{k} " + " ".join(f"{x:.3f}" for x in v[:2])
                for k, v in r.items() if k != "load"), flush=True)
    med = lambda key, i: statistics.median(r[key][i] for r in rounds)
    splits = rounds[0]["new stream"][2]
    summary = {"loads": [r["load"] for r in rounds], "rounds": a.rounds, "splits": splits,
               "draco_decode_elapsed_s": med("draco decode", 0),
               "draco_decode_cpu_s": med("draco decode", 1)}
    for name, _, _ in sides:
        splits = rounds[0][name + " stream"][2]
        summary[name] = {
            "decode_elapsed_s": med(name + " decode", 0),
            "decode_cpu_s": med(name + " decode", 1),
            "decode_cpu_vs_draco": statistics.median(
                r[name + " decode"][1] / r["draco decode"][1] for r in rounds),
            "decode_elapsed_vs_draco": statistics.median(
                r[name + " decode"][0] / r["draco decode"][0] for r in rounds),
            "decode_1t_elapsed_s": med(name + " decode-1t", 0),
            "decode_1t_cpu_s": med(name + " decode-1t", 1),
            "decode_1t_elapsed_vs_draco": statistics.median(
                r[name + " decode-1t"][0] / r["draco decode"][0] for r in rounds),
            "stream_cpu_s": med(name + " stream", 1),
            "stream_splits_per_cpu_s": splits / med(name + " stream", 1),
            "first_refinement_cpu_ms": med(name + " info", 0),
            "rerefinement_cpu_ms": med(name + " info", 1),
            "rerefinement_splits_per_cpu_s": splits / (med(name + " info", 1) / 1e3),
        }
    print(json.dumps(summary))


if __name__ == "__main__":
    sys.exit(main())
