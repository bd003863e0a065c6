#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The tools' command-line conventions, one check per case:
`-` for stdin/stdout (pmz-encode, pmz-decode, pmz-compare), outputs through symlinks / onto devices and FIFOs / onto the input,
temporaries removed on error and on signals, one-line errors with the reason, exit codes
(0 ok, 1 failure, 2 usage), defaults in --help, the progress bar, pmz-info without decoding
and on truncated files, unreachable decode targets, --faces 0 / --ratio 0 as the base mesh,
batch encoding with --out-dir and -j, the encodes' memory budget (--memory), an encode split
into tasks (--plan, --task with GNU parallel, --assemble), one definition of the simplifier's
options (pmz-encode and pmz-simplify).

usage: test_cli.py BIN_DIR SAMPLE_OBJ SAMPLE_PMZ WORK_DIR [CASE...]
BIN_DIR holds pmz-encode, pmz-decode, pmz-info, pmz-simplify, pmz-compare (pmz-view optional).
Exits 1 listing the failed cases."""
import json
import math
import os
import pty
import re
import resource
import select
import shutil
import signal
import stat
import struct
import subprocess
import sys
import time
import zlib

BIN, SAMPLE_OBJ, SAMPLE_PMZ, WORK = (os.path.abspath(a) for a in sys.argv[1:5])
ONLY = sys.argv[5:]
TOOLS = ["pmz-encode", "pmz-decode", "pmz-info", "pmz-simplify", "pmz-compare"]


def tool(name):
    return os.path.join(BIN, name)


def run(args, **kw):
    kw.setdefault("stdout", subprocess.PIPE)
    kw.setdefault("stderr", subprocess.PIPE)
    kw.setdefault("timeout", 120)
    return subprocess.run(args, **kw)


class Failed(Exception):
    pass


def check(cond, what):
    if not cond:
        raise Failed(what)


def err_text(r):
    return r.stderr.decode(errors="replace")


def fresh(name):
    d = os.path.join(WORK, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    return d


def sample_bytes():
    with open(SAMPLE_PMZ, "rb") as f:
        return f.read()


def info_json(path):
    r = run([tool("pmz-info"), "--json", path])
    check(r.returncode == 0, f"pmz-info --json {path}: rc={r.returncode} {err_text(r)}")
    return json.loads(r.stdout)


# ---- `-` for stdin and stdout ----

def case_encode_to_stdout():
    d = fresh("encode_stdout")
    ref = os.path.join(d, "ref.pmz")
    r = run([tool("pmz-encode"), SAMPLE_OBJ, "-o", ref])
    check(r.returncode == 0, f"encode to a file: rc={r.returncode} {err_text(r)}")
    r = run([tool("pmz-encode"), SAMPLE_OBJ, "-o", "-"], cwd=d)
    check(r.returncode == 0, f"encode -o -: rc={r.returncode} {err_text(r)}")
    check(not os.path.exists(os.path.join(d, "-")), "encode -o - created a file named '-'")
    check(r.stdout == open(ref, "rb").read(), "encode -o - did not write the stream to stdout")


def case_decode_from_stdin_to_stdout():
    d = fresh("decode_stdio")
    ref = os.path.join(d, "ref.obj")
    r = run([tool("pmz-decode"), SAMPLE_PMZ, "-o", ref])
    check(r.returncode == 0, f"decode to a file: rc={r.returncode} {err_text(r)}")
    r = run([tool("pmz-decode"), "-", "-o", os.path.join(d, "in.obj")], input=sample_bytes())
    check(r.returncode == 0, f"pmz-decode - (stdin): rc={r.returncode} {err_text(r)}")
    check(open(os.path.join(d, "in.obj"), "rb").read() == open(ref, "rb").read(),
          "decoding stdin gave another mesh than decoding the file")
    r = run([tool("pmz-decode"), SAMPLE_PMZ, "-o", "-", "--format", "obj"], cwd=d)
    check(r.returncode == 0, f"pmz-decode -o - --format obj: rc={r.returncode} {err_text(r)}")
    check(r.stdout == open(ref, "rb").read(), "pmz-decode -o - did not write the mesh to stdout")
    r = run([tool("pmz-decode"), SAMPLE_PMZ, "-o", "-"], cwd=d)
    check(r.returncode == 2 and b"--format" in r.stderr,
          f"pmz-decode -o - without --format: expected exit 2 naming --format, got "
          f"{r.returncode}: {err_text(r)}")


def case_encode_from_stdin():
    d = fresh("encode_stdin")
    ref = os.path.join(d, "ref.pmz")
    run([tool("pmz-encode"), SAMPLE_OBJ, "-o", ref])
    mesh = open(SAMPLE_OBJ, "rb").read()
    out = os.path.join(d, "stdin.pmz")
    r = run([tool("pmz-encode"), "-", "--format", "obj", "-o", out], input=mesh)
    check(r.returncode == 0, f"pmz-encode - --format obj: rc={r.returncode} {err_text(r)}")
    check(open(out, "rb").read() == open(ref, "rb").read(),
          "encoding stdin gave another stream than encoding the file")
    r = run([tool("pmz-encode"), "-", "-o", out], input=mesh)
    check(r.returncode == 2 and b"--format" in r.stderr,
          f"pmz-encode - without --format: expected exit 2 naming --format, got {r.returncode}")
    r = run([tool("pmz-encode"), "-", "--format", "obj", "-o", out], input=b"v 0 0 nan\n")
    check(r.returncode == 1 and err_text(r).startswith("pmz-encode: stdin: "),
          f"bad mesh on stdin: expected exit 1 and 'pmz-encode: stdin: ...', got "
          f"{r.returncode}: {err_text(r)}")


def grid_mesh_files(d, n):
    """An n x n grid (two triangles per cell) written in every format the readers take apart from
    glTF, ascii and binary: {file name: path}. Written as generated: the test process stays small
    (the tools it starts would report its resident set as theirs)."""
    def vert(i):
        return (i % n * 0.125, i // n * 0.25, ((i * 7919) % 13) * -0.0625)

    def faces():
        for r in range(n - 1):
            for c in range(n - 1):
                a = r * n + c
                yield (a, a + 1, a + n + 1)
                yield (a, a + n + 1, a + n)

    nv, nf = n * n, 2 * (n - 1) * (n - 1)
    text = lambda v: " ".join(repr(x) for x in v)
    ply_head = ("ply\nformat {} 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                "property float z\nelement face %d\nproperty list uchar int vertex_indices\n"
                "end_header\n") % (nv, nf)

    def ascii_ply(w):
        w(ply_head.format("ascii").encode())
        for i in range(nv):
            w((text(vert(i)) + "\n").encode())
        for f in faces():
            w(b"3 %d %d %d\n" % f)

    def binary_ply(w):
        w(ply_head.format("binary_little_endian").encode())
        for i in range(nv):
            w(struct.pack("<3f", *vert(i)))
        for f in faces():
            w(struct.pack("<B3i", 3, *f))

    def obj(w):
        for i in range(nv):
            w(("v %s\n" % text(vert(i))).encode())
        for f in faces():
            w(b"f %d %d %d\n" % tuple(i + 1 for i in f))

    def off(w):
        w(b"OFF\n%d %d 0\n" % (nv, nf))
        for i in range(nv):
            w((text(vert(i)) + "\n").encode())
        for f in faces():
            w(b"3 %d %d %d\n" % f)

    def binary_off(w):
        w(b"OFF BINARY\n" + struct.pack("<3i", nv, nf, 0))
        for i in range(nv):
            w(struct.pack("<3f", *vert(i)))
        for f in faces():
            w(struct.pack("<4i", 3, *f))

    def ascii_stl(w):
        w(b"solid grid\n")
        for f in faces():
            w(("facet normal 0 0 1\nouter loop\n" +
               "".join("vertex %s\n" % text(vert(i)) for i in f) + "endloop\nendfacet\n").encode())
        w(b"endsolid grid\n")

    def binary_stl(w):
        w(b" " * 80 + struct.pack("<I", nf))
        for f in faces():
            w(struct.pack("<3f", 0, 0, 1) + b"".join(struct.pack("<3f", *vert(i)) for i in f) +
              b"\0\0")

    writers = {"grid.ply": ascii_ply, "grid-binary.ply": binary_ply, "grid.obj": obj,
               "grid.off": off, "grid-binary.off": binary_off, "grid.stl": ascii_stl,
               "grid-binary.stl": binary_stl}
    paths = {}
    for name, write in writers.items():
        paths[name] = os.path.join(d, name)
        with open(paths[name], "wb") as f:
            write(f.write)
    return paths


def encode_piped(path, args):
    """pmz-encode ARGS with the file's bytes on stdin through a pipe (cat | pmz-encode)."""
    cat = subprocess.Popen(["cat", path], stdout=subprocess.PIPE)
    r = run([tool("pmz-encode")] + args, stdin=cat.stdout)
    cat.stdout.close()
    cat.wait()
    return r


def case_encode_from_a_pipe_in_every_format():
    # Each reader streams stdin (larger than its 1 MiB window here): a pipe, or a file given as
    # stdin, encodes to the bytes of the file given by its path; cut short, it gives the error
    # of the cut file.
    d = fresh("encode_pipe_formats")
    for name, path in grid_mesh_files(d, 240).items():
        fmt = os.path.splitext(name)[1][1:]
        ref, out = os.path.join(d, name + ".pmz"), os.path.join(d, name + ".stdin.pmz")
        r = run([tool("pmz-encode"), path, "-o", ref])
        check(r.returncode == 0, f"pmz-encode {name}: rc={r.returncode} {err_text(r)}")
        size = os.path.getsize(path)
        check(size > 1 << 20, f"{name} is not larger than the read window")
        r = encode_piped(path, ["-", "--format", fmt, "-o", out])
        check(r.returncode == 0, f"pmz-encode - --format {fmt} ({name}): rc={r.returncode} "
              f"{err_text(r)}")
        check(open(out, "rb").read() == open(ref, "rb").read(),
              f"{name} through a pipe gave another stream than the file")
        with open(path, "rb") as f:
            r = run([tool("pmz-encode"), "-", "--format", fmt, "-o", out], stdin=f)
        check(r.returncode == 0 and open(out, "rb").read() == open(ref, "rb").read(),
              f"{name} as stdin gave another stream than the file: {err_text(r)}")
        cut = os.path.join(d, "cut-" + name)
        shutil.copy(path, cut)
        os.truncate(cut, size * 2 // 3)
        r_file = run([tool("pmz-encode"), cut, "-o", out])
        r_pipe = encode_piped(cut, ["-", "--format", fmt, "-o", out])
        check(r_file.returncode == r_pipe.returncode and
              err_text(r_pipe) == err_text(r_file).replace(cut, "stdin"),
              f"{name} cut short: the pipe said {r_pipe.returncode} {err_text(r_pipe)!r}, the "
              f"file {r_file.returncode} {err_text(r_file)!r}")


def case_compare_from_stdin():
    d = fresh("compare_stdin")
    half = os.path.join(d, "half.obj")
    r = run([tool("pmz-simplify"), SAMPLE_OBJ, "--ratio", "0.5", "-o", half])
    check(r.returncode == 0, f"pmz-simplify: rc={r.returncode} {err_text(r)}")

    def measured(args, stdin=None):
        r = run([tool("pmz-compare"), "--json"] + args, input=stdin)
        check(r.returncode == 0, f"pmz-compare {args}: rc={r.returncode} {err_text(r)}")
        j = json.loads(r.stdout)
        j.pop("seconds")
        return j

    ref = measured([SAMPLE_OBJ, half])
    check(ref["max"] > 0, f"the halved mesh measured no error: {ref}")
    check(measured(["-", half, "--format", "obj"], open(SAMPLE_OBJ, "rb").read()) == ref,
          "ORIGINAL from stdin measured another result than from the file")
    check(measured([SAMPLE_OBJ, "-", "--format", "obj"], open(half, "rb").read()) == ref,
          "OTHER from stdin measured another result than from the file")
    r = run([tool("pmz-compare"), SAMPLE_OBJ, "-", "--format", "obj"], input=open(half, "rb").read())
    check(r.returncode == 0 and "other:    stdin (" in r.stdout.decode(),
          f"the text report does not name stdin: {r.stdout.decode()[:200]!r}")
    r = run([tool("pmz-compare"), SAMPLE_OBJ, "-"], input=open(half, "rb").read())
    check(r.returncode == 2 and err_text(r).startswith("pmz-compare: ") and b"--format" in r.stderr,
          f"- without --format: expected exit 2 naming --format, got {r.returncode}: {err_text(r)}")
    r = run([tool("pmz-compare"), "-", "-", "--format", "obj"], input=b"")
    check(r.returncode == 2 and "stdin given twice" in err_text(r),
          f"- twice: expected exit 2, got {r.returncode}: {err_text(r)}")
    r = run([tool("pmz-compare"), SAMPLE_OBJ, "-", "--format", "obj"], input=b"v 0 0 nan\n")
    check(r.returncode == 1 and err_text(r).startswith("pmz-compare: stdin: "),
          f"bad mesh on stdin: expected exit 1 and 'pmz-compare: stdin: ...', got "
          f"{r.returncode}: {err_text(r)}")


# ---- one definition of the simplifier's options ----

def simplifier_option_lines(name):
    r = run([tool(name), "--help"])
    check(r.returncode == 0, f"{name} --help: rc={r.returncode}")
    lines = r.stdout.decode().splitlines()
    names = ["--metric", "--attributes", "--attribute-weight", "--epsilon", "--quadric-floor",
             "--torsion-weight", "--boundary-weight", "--quadric-memory", "--guard-slack"]
    start = next((i for i, l in enumerate(lines) if l.strip().startswith("--metric")), None)
    end = next((i for i, l in enumerate(lines) if l.strip().startswith("--guard-slack")), None)
    check(start is not None and end is not None, f"{name} --help lacks --metric or --guard-slack")
    block = lines[start:end + 1]
    for n in names:
        check(any(l.strip().startswith(n + " ") for l in block), f"{name} --help lacks {n}")
    return block


def case_simplifier_options_shared():
    encode, simplify = (simplifier_option_lines(n) for n in ("pmz-encode", "pmz-simplify"))
    check(encode == simplify, "pmz-encode and pmz-simplify describe the simplifier's options "
          f"differently:\n{encode}\n{simplify}")
    d = fresh("simplifier_options")
    outs = {}
    for key, extra in [("default", []), ("explicit", ["--epsilon", "0.3", "--guard-slack", "0.8"]),
                       ("epsilon", ["--epsilon", "0.9"]), ("qem", ["--metric", "qem"])]:
        outs[key] = os.path.join(d, key + ".pmz")
        r = run([tool("pmz-encode"), SAMPLE_OBJ, "-o", outs[key]] + extra)
        check(r.returncode == 0, f"pmz-encode {extra}: rc={r.returncode} {err_text(r)}")
    data = {k: open(p, "rb").read() for k, p in outs.items()}
    check(data["explicit"] == data["default"], "the defaults given explicitly changed the stream")
    check(data["epsilon"] != data["default"], "pmz-encode --epsilon did not reach the simplifier")
    check(data["qem"] != data["default"], "pmz-encode --metric qem did not reach the simplifier")


# ---- where outputs go ----

def case_symlink_output_keeps_link():
    d = fresh("symlink")
    for name, args in [("pmz-encode", [SAMPLE_OBJ]), ("pmz-decode", [SAMPLE_PMZ]),
                       ("pmz-simplify", [SAMPLE_OBJ, "--ratio", "0.5"])]:
        ext = ".pmz" if name == "pmz-encode" else ".obj"
        target = os.path.join(d, name + "-target" + ext)
        link = os.path.join(d, name + "-link" + ext)
        with open(target, "w") as f:
            f.write("old")
        os.chmod(target, 0o640)
        os.symlink(os.path.basename(target), link)
        r = run([tool(name)] + args + ["-o", link])
        check(r.returncode == 0, f"{name} -o symlink: rc={r.returncode} {err_text(r)}")
        check(os.path.islink(link), f"{name} replaced the symlink by a file")
        check(open(target, "rb").read() != b"old", f"{name} did not update the link's target")
        check(stat.S_IMODE(os.stat(target).st_mode) == 0o640,
              f"{name} changed the target's permissions")
        check(sorted(os.listdir(d)).count(os.path.basename(target)) == 1, "stray files")
    left = [f for f in os.listdir(d) if f.startswith(".")]
    check(not left, f"temporaries left: {left}")


def mknod_or_none(path, minor):
    try:
        os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, minor))
        return path
    except (PermissionError, OSError):
        return None


def case_device_written_directly():
    # Private copies of /dev/null (1,3) and /dev/full (1,7): an old binary that renames over
    # them destroys only these.
    d = fresh("device")
    null = mknod_or_none(os.path.join(d, "null"), 3)
    full = mknod_or_none(os.path.join(d, "full"), 7)
    if not null or not full:
        print("  (skipped: mknod not permitted)")
        return
    for name, args in [("pmz-encode", [SAMPLE_OBJ]),
                       ("pmz-decode", [SAMPLE_PMZ, "--format", "obj"])]:
        r = run([tool(name)] + args + ["-o", null])
        check(r.returncode == 0, f"{name} -o null device: rc={r.returncode} {err_text(r)}")
        check(stat.S_ISCHR(os.stat(null).st_mode), f"{name} replaced the device node")
        r = run([tool(name)] + args + ["-o", full])
        e = err_text(r)
        check(r.returncode == 1 and stat.S_ISCHR(os.stat(full).st_mode),
              f"{name} -o full device: expected exit 1 and the node kept, got {r.returncode}")
        check(e == f"{name}: {full}: cannot write: No space left on device\n",
              f"{name} on a full device: expected one line with the reason, got: {e!r}")
    left = sorted(set(os.listdir(d)) - {"null", "full"})
    check(not left, f"files left beside the devices: {left}")


def case_fifo_written_directly():
    d = fresh("fifo")
    fifo = os.path.join(d, "pipe.pmz")
    os.mkfifo(fifo)
    # The read end opened first (non-blocking): the tool's open for writing then succeeds, and
    # the small stream fits the pipe's buffer.
    fd = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)
    r = run([tool("pmz-encode"), SAMPLE_OBJ, "-o", fifo], timeout=30)
    got = {"data": b""}
    try:
        while chunk := os.read(fd, 65536):
            got["data"] += chunk
    except BlockingIOError:
        pass
    os.close(fd)
    check(r.returncode == 0, f"pmz-encode -o FIFO: rc={r.returncode} {err_text(r)}")
    check(stat.S_ISFIFO(os.stat(fifo).st_mode), "the FIFO was replaced by a file")
    ref = os.path.join(d, "ref.pmz")
    run([tool("pmz-encode"), SAMPLE_OBJ, "-o", ref])
    check(got.get("data") == open(ref, "rb").read(), "the stream did not come through the FIFO")


def case_output_is_input_refused():
    d = fresh("same")
    mesh = os.path.join(d, "m.obj")
    shutil.copy(SAMPLE_OBJ, mesh)
    hard = os.path.join(d, "hard.obj")
    os.link(mesh, hard)
    before = open(mesh, "rb").read()
    for args, name in [(["pmz-encode", mesh, "-o", mesh], "encode a -o a"),
                       (["pmz-encode", mesh, "-o", hard], "encode a -o hard link of a"),
                       (["pmz-simplify", mesh, "-o", hard, "--ratio", "0.5"], "simplify")]:
        r = run([tool(args[0])] + args[1:])
        check(r.returncode == 1, f"{name}: expected exit 1, got {r.returncode}: {err_text(r)}")
        check("input" in err_text(r), f"{name}: message does not say why: {err_text(r)}")
        check(open(mesh, "rb").read() == before, f"{name}: the input was overwritten")
    pmz = os.path.join(d, "s.pmz")
    shutil.copy(SAMPLE_PMZ, pmz)
    r = run([tool("pmz-decode"), pmz, "-o", pmz, "--format", "obj"])
    check(r.returncode == 1 and open(pmz, "rb").read() == sample_bytes(),
          f"pmz-decode a -o a: expected refusal, got {r.returncode}: {err_text(r)}")


def case_write_error_names_output_and_reason():
    d = fresh("fsize")
    out = os.path.join(d, "big.obj")

    def cap():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (1000, 1000))

    r = run([tool("pmz-decode"), SAMPLE_PMZ, "-o", out], preexec_fn=cap)
    e = err_text(r)
    check(r.returncode == 1, f"write beyond the file-size cap: expected exit 1, got {r.returncode}")
    check(e == f"pmz-decode: {out}: cannot write: File too large\n",
          f"expected one line naming the output and the reason, got {e!r}")
    check(os.listdir(d) == [], f"left behind: {os.listdir(d)}")
    r = run([tool("pmz-encode"), SAMPLE_OBJ, "-o", os.path.join(d, "no", "such", "dir.pmz")])
    e = err_text(r)
    check(r.returncode == 1 and e.startswith("pmz-encode: ") and "No such file or directory" in e
          and ".tmp" not in e and e.count("\n") == 1,
          f"missing folder: expected one line with the reason and no temporary's name: {e!r}")


def wait_for_temporary(d, p, seconds=20):
    t0 = time.time()
    while time.time() - t0 < seconds:
        if p.poll() is not None:
            return None
        names = [f for f in os.listdir(d) if f.startswith(".")]
        if names:
            return names
        time.sleep(0.02)
    return None


def case_signal_removes_temporary():
    for sig in (signal.SIGINT, signal.SIGTERM):
        for name, args in [("pmz-decode", ["-", "-o", "out.obj"]),
                           ("pmz-encode", ["-", "--format", "obj", "-o", "out.pmz"])]:
            d = fresh(f"signal_{name}_{int(sig)}")
            # stdin stays open: the tool has opened its output and waits for its input.
            p = subprocess.Popen([tool(name)] + args, cwd=d, stdin=subprocess.PIPE,
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE)
            temps = wait_for_temporary(d, p)
            if temps is None:
                p.kill()
                _, e = p.communicate()
                raise Failed(f"{name}: no temporary output while reading stdin (rc={p.returncode}"
                             f"): {e.decode(errors='replace')}")
            p.send_signal(sig)
            p.stdin.close()
            p.wait(30)
            check(p.returncode == -sig,
                  f"{name}: expected death by signal {int(sig)}, got rc={p.returncode}")
            check(os.listdir(d) == [], f"{name}: after signal {int(sig)} left {os.listdir(d)}")


# ---- messages and exit codes ----

def case_exit_codes_and_one_line_errors():
    d = fresh("exit")
    for name in TOOLS:
        r = run([tool(name), "--no-such-option"])
        e = err_text(r)
        check(r.returncode == 2, f"{name} --no-such-option: expected exit 2, got {r.returncode}")
        check(e.startswith(name + ": "), f"{name}: usage error does not name the tool: {e!r}")
        r = run([tool(name), "--help"])
        check(r.returncode == 0 and b"Exit status: 0 success, 1 failure" in r.stdout,
              f"{name} --help: expected exit 0 and the exit-code convention")
    missing = os.path.join(d, "missing.pmz")
    for name, args in [("pmz-decode", [missing, "-o", os.path.join(d, "x.obj")]),
                       ("pmz-info", [missing])]:
        r = run([tool(name)] + args)
        e = err_text(r)
        check(r.returncode == 1 and e == f"{name}: {missing}: cannot read: No such file or "
              "directory\n", f"{name} on a missing file: expected exit 1 and one line with "
              f"file and reason, got {r.returncode}: {e!r}")
    trunc = os.path.join(d, "trunc.pmz")
    open(trunc, "wb").write(sample_bytes()[:300])
    r = run([tool("pmz-decode"), trunc, "-o", os.path.join(d, "t.obj")])
    check(r.returncode == 1 and err_text(r).startswith(f"pmz-decode: {trunc}: "),
          f"pmz-decode on a truncated file: the error does not name the file: {err_text(r)!r}")


def damaged_streams(d):
    """An empty file, one cut short, one with a bad magic, one with a corrupt chunk."""
    data = sample_bytes()
    corrupt = bytearray(data)
    corrupt[len(data) // 2] ^= 0xFF
    files = {"empty": b"", "truncated": data[:300], "bad_magic": b"XXXX" + data[4:],
             "corrupt": bytes(corrupt)}
    paths = {}
    for name, content in files.items():
        paths[name] = os.path.join(d, name + ".pmz")
        open(paths[name], "wb").write(content)
    return paths


def one_line_reason(name, path, r):
    """The reason of a one-line error 'name: path: reason', or a failure."""
    e = err_text(r)
    check(r.returncode == 1, f"{name} {path}: expected exit 1, got {r.returncode}: {e!r}")
    check(e.count("\n") == 1 and e.startswith(f"{name}: {path}: "),
          f"{name} {path}: expected one line '{name}: {path}: reason', got {e!r}")
    reason = e[len(f"{name}: {path}: "):-1]
    check("pmz: " not in reason, f"{name} {path}: the library's prefix inside the message: {e!r}")
    return reason


def case_damaged_stream_one_line_every_tool():
    d = fresh("damaged")
    view = tool("pmz-view")
    has_view = os.path.exists(view) and shutil.which("xvfb-run")
    for kind, path in damaged_streams(d).items():
        out = os.path.join(d, "out.obj")
        reason = one_line_reason("pmz-decode", path, run([tool("pmz-decode"), path, "-o", out]))
        check(not os.path.exists(out), f"pmz-decode wrote {out} for a {kind} stream")
        nothing = "; nothing written (--salvage writes the last good level)"
        check(reason.endswith(nothing), f"pmz-decode {kind}: does not say nothing was written: "
              f"{reason!r}")
        reason = reason[:-len(nothing)]
        if kind == "empty":
            check(reason == "empty file", f"an empty .pmz: expected 'empty file', got {reason!r}")
        if kind != "truncated":  # pmz-info describes a truncated file (exit 0)
            got = one_line_reason("pmz-info", path, run([tool("pmz-info"), path]))
            check(got == reason, f"pmz-info words a {kind} stream otherwise: {got!r} vs {reason!r}")
        if has_view:
            got = one_line_reason("pmz-view", path, run(
                ["xvfb-run", "-a", view, path, "--screenshot", os.path.join(d, "v.png"), "--size",
                 "64x64"]))
            check(got == reason, f"pmz-view words a {kind} stream otherwise: {got!r} vs {reason!r}")
    # Damaged meshes: the same reason from every tool that reads them.
    meshes = {"empty.obj": "", "truncated.ply": "ply\nformat binary_little_endian 1.0\nelement "
              "vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n\1\2",
              "bad_magic.ply": "plx\nformat ascii 1.0\n", "corrupt.obj": "v 0 0 0\nf 1 2 zz\n"}
    for name, text in meshes.items():
        path = os.path.join(d, name)
        open(path, "w").write(text)
        reasons = {one_line_reason(t, path, run([tool(t)] + args)) for t, args in [
            ("pmz-encode", [path, "-o", os.path.join(d, "m.pmz")]),
            ("pmz-simplify", [path, "--ratio", "0.5", "-o", os.path.join(d, "m.obj")]),
            ("pmz-compare", [SAMPLE_OBJ, path])]}
        check(len(reasons) == 1, f"{name}: the tools word it differently: {reasons}")
    left = [f for f in os.listdir(d) if f.startswith(".") or f in ("m.pmz", "m.obj", "out.obj")]
    check(not left, f"left behind: {left}")


def case_stale_temporary_removed():
    d = fresh("stale")
    scratch = fresh("stale_tmpdir")  # TMPDIR: where stdin is parsed under a scratch file's name
    env = dict(os.environ, TMPDIR=scratch)
    out = os.path.join(d, "out.pmz")
    # SIGKILL cannot be caught: the temporaries stay, named after the dead process.
    p = subprocess.Popen([tool("pmz-encode"), "-", "--format", "obj", "-o", out], env=env,
                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    temps = wait_for_temporary(d, p)
    if temps is None:
        p.kill()
        raise Failed("pmz-encode: no temporary output while reading stdin")
    p.kill()
    p.wait(30)
    check(temps == [f".out.pmz.tmp.{p.pid}." + temps[0][-6:]],
          f"the temporary does not carry the writer's PID {p.pid}: {temps}")
    left = os.listdir(scratch)
    check(len(left) == 1 and left[0].startswith(f"pmz-encode.{p.pid}.") and
          left[0].endswith(".obj"), f"the scratch file does not carry the PID {p.pid}: {left}")
    live = f".out.pmz.tmp.{os.getpid()}.abcdef"  # a running process's: still being written
    other = f".other.pmz.tmp.{p.pid}.abcdef"      # another output's: not this run's to remove
    for name in (live, other):
        open(os.path.join(d, name), "w").close()
    live_scratch = f"pmz-encode.{os.getpid()}.abcdef.obj"  # a running process's
    other_scratch = f"pmz-encode.{p.pid}.abcdef.ply"       # another format's name
    for name in (live_scratch, other_scratch):
        open(os.path.join(scratch, name), "w").close()
    r = run([tool("pmz-encode"), SAMPLE_OBJ, "-o", out])
    check(r.returncode == 0, f"pmz-encode after a kill: rc={r.returncode} {err_text(r)}")
    check(sorted(os.listdir(d)) == sorted(["out.pmz", live, other]),
          f"the dead run's temporary is not removed (or another is): {sorted(os.listdir(d))}")
    # The next run parsing stdin in that format removes the dead run's scratch file.
    with open(SAMPLE_OBJ, "rb") as f:
        r = run([tool("pmz-encode"), "-", "--format", "obj", "-o", out], env=env, stdin=f)
    check(r.returncode == 0, f"pmz-encode from stdin after a kill: rc={r.returncode} {err_text(r)}")
    check(sorted(os.listdir(scratch)) == sorted([live_scratch, other_scratch]),
          f"the dead run's scratch file is not removed (or another is): {os.listdir(scratch)}")


def case_progress_bar_ends_before_messages():
    d = fresh("progress_messages")
    quad = os.path.join(d, "quad.obj")
    # A polygon: reading reports its triangulation on stderr while the bar is shown.
    with open(quad, "w") as f:
        f.write("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    r = run([tool("pmz-encode"), quad, "-o", os.path.join(d, "q.pmz"), "--progress"])
    e = err_text(r)
    check(r.returncode == 0, f"pmz-encode --progress: rc={r.returncode} {e!r}")
    note = [l for l in e.split("\n") if "triangulated" in l]
    check(note == [f"pmz-encode: {quad}: triangulated 1 polygon into 2 triangles"],
          f"the repair note is not a line of its own: {e!r}")
    check("reading [" + "=" * 30 + "] 100%" in e,
          f"the reading stage does not report its progress: {e!r}")
    # Reading a larger file reports steps between 0 and 100%.
    big = os.path.join(d, "big.obj")
    with open(big, "w") as f:
        f.write("# padding\n" * 200000 + open(SAMPLE_OBJ).read())
    r = run([tool("pmz-encode"), big, "-o", os.path.join(d, "b.pmz"), "--progress"])
    stages = [p.strip() for p in err_text(r).replace("\n", "\r").split("\r") if "reading [" in p]
    check(r.returncode == 0 and any(not s.endswith((" 0%", "100%")) for s in stages),
          f"reading a {os.path.getsize(big)}-byte file went from 0 to 100% at once: {stages}")


def case_help_shows_defaults():
    r = run([tool("pmz-encode"), "--help"])
    h = r.stdout.decode()
    for opt, default in [("--position-bits", "=14"), ("--metric", "=guarded"),
                         ("--base-faces", "=0"), ("--jobs", "=")]:
        line = next((l for l in h.splitlines() if opt in l), "")
        check(default in line, f"pmz-encode --help: {opt} does not show its default: {line!r}")
    r = run([tool("pmz-simplify"), "--help"])
    line = next((l for l in r.stdout.decode().splitlines() if "--epsilon" in l), "")
    check("=0.3" in line, f"pmz-simplify --help: --epsilon without its default: {line!r}")


def read_pty(master):
    data = b""
    while True:
        ready, _, _ = select.select([master], [], [], 0.5)
        if not ready:
            return data
        try:
            chunk = os.read(master, 65536)
        except OSError:
            return data
        if not chunk:
            return data
        data += chunk


def case_progress_bar():
    d = fresh("progress")
    out = os.path.join(d, "o.pmz")
    r = run([tool("pmz-encode"), SAMPLE_OBJ, "-o", out])
    check(b"\r" not in r.stderr and r.stderr == b"",
          f"progress on a redirected stderr without --progress: {r.stderr!r}")
    r = run([tool("pmz-encode"), SAMPLE_OBJ, "-o", out, "--progress"])
    check(r.returncode == 0 and b"%" in r.stderr and b"simplifying" in r.stderr,
          f"--progress: no bar on stderr: {r.stderr!r}")
    for quiet in (False, True):
        master, slave = pty.openpty()
        p = subprocess.Popen([tool("pmz-encode"), SAMPLE_OBJ, "-o", out] +
                             (["--quiet"] if quiet else []), stdout=subprocess.PIPE,
                             stderr=slave)
        os.close(slave)
        p.communicate(timeout=60)
        seen = read_pty(master)
        os.close(master)
        if quiet:
            check(seen == b"", f"--quiet on a terminal still printed {seen!r}")
        else:
            check(b"%" in seen, f"no progress bar on a terminal: {seen!r}")


# ---- pmz-info and decode targets ----

def case_info_without_decoding():
    r = run([tool("pmz-info"), SAMPLE_PMZ])
    o = r.stdout.decode()
    check(r.returncode == 0 and "full refinement" not in o,
          f"pmz-info decodes and times by default: {o!r}")
    r = run([tool("pmz-info"), SAMPLE_PMZ, "--decode"])
    check(r.returncode == 0 and "full refinement" in r.stdout.decode(),
          "pmz-info --decode does not time the refinement")
    j = info_json(SAMPLE_PMZ)
    check("refine_cpu_ms" not in j and j.get("complete") is True,
          f"pmz-info --json: timing without --decode or no 'complete': {j}")


def case_info_describes_truncated_file():
    d = fresh("info_trunc")
    data = sample_bytes()
    whole = info_json(SAMPLE_PMZ)
    for cut in (120, 300, len(data) - 3):
        path = os.path.join(d, f"cut{cut}.pmz")
        open(path, "wb").write(data[:cut])
        r = run([tool("pmz-info"), path])
        o = r.stdout.decode()
        check(r.returncode == 0, f"pmz-info on {cut} of {len(data)} bytes: rc={r.returncode} "
              f"{err_text(r)}")
        check("truncated" in o and f"of {whole['splits']} splits available" in o,
              f"pmz-info on {cut} bytes does not say what is there: {o!r}")
        j = info_json(path)
        check(j["complete"] is False and j["full_faces"] == whole["full_faces"] and
              j["splits_available"] <= whole["splits"] and
              (cut > 300 or j["splits_available"] < whole["splits"]),
              f"pmz-info --json on {cut} bytes: {j}")


def case_info_decode_of_truncated_file():
    d = fresh("info_trunc_decode")
    data = sample_bytes()
    path = os.path.join(d, "cut.pmz")
    open(path, "wb").write(data[:len(data) - 3])
    r = run([tool("pmz-info"), path, "--decode"])
    check(r.returncode == 0 and "truncated" in r.stdout.decode() and
          "full refinement" in r.stdout.decode(),
          f"pmz-info --decode on a truncated file: rc={r.returncode} {err_text(r)!r}")


SEAMED = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "conformance")


def attribute_bytes_add_up(j, what):
    a = j.get("attributes")
    check(a is not None and j.get("attribute_bytes_counted") is True,
          f"pmz-info --json {what}: no attributes counted: {j}")
    total = sum(e["bytes"] for e in a.values())
    check(total == j["attribute_bytes"] and j["other_bytes"] >= j["attribute_bytes"] > 0,
          f"{what}: the entries' bytes add up to {total}, not attribute_bytes: {j}")
    # Every symbol is counted: what is left is the chunk headers and the coder's start and end.
    check(0 < a["framing"]["bytes"] <= 16 * j["attribute_chunks"],
          f"{what}: {a['framing']['bytes']} bytes of framing in {j['attribute_chunks']} ATTR "
          f"chunks: {a}")
    return a


def case_info_attribute_kinds():
    # seamed-coarse: texture coordinates, normals, colours (6, 4 and 3 bits) and 2 materials.
    path = os.path.join(SEAMED, "vectors", "seamed-coarse.pmz")
    j = info_json(path)
    a = attribute_bytes_add_up(j, "seamed-coarse.pmz")
    want = {"texcoords": ("texture coordinates", 6), "normals": ("normals", 4),
            "colors": ("colours", 3)}
    for key, (name, bits) in want.items():
        check(key in a and a[key]["name"] == name and a[key]["bits"] == bits and
              a[key]["bytes"] > 0, f"seamed-coarse.pmz: {key} should be {name}, {bits} bits, "
              f"some bytes: {a}")
    check(a["materials"]["count"] == 2 and a["materials"]["bytes"] > 0 and a["wedges"]["bytes"] > 0,
          f"seamed-coarse.pmz: materials or wedge references: {a}")
    r = run([tool("pmz-info"), path])
    o = r.stdout.decode()
    for line in ("texture coordinates  1 set, 6 bits", "normals              octahedral, 4 bits",
                 "colours              RGB, 3 bits", f"attributes {j['attribute_bytes']} bytes"):
        check(line in o, f"pmz-info seamed-coarse.pmz does not say {line!r}: {o}")
    # --decode times another decoder: the counts are the same.
    r = run([tool("pmz-info"), "--json", "--decode", path])
    check(r.returncode == 0 and json.loads(r.stdout)["attributes"] == a,
          f"pmz-info --decode counts otherwise: {r.stdout!r}")


def chunk_frames(path):
    # (type, whole size) of each chunk of a stream: after the 8-byte signature, type, varint
    # size, CRC, payload.
    data, at, frames = open(path, "rb").read(), 8, []
    while at < len(data):
        start, size, shift, at = at, 0, 0, at + 1
        while True:
            size |= (data[at] & 0x7F) << shift
            at, shift = at + 1, shift + 7
            if not data[at - 1] & 0x80:
                break
        at += 4 + size
        frames.append((data[start], at - start))
    return frames


def chunk_types(path):
    return [t for t, _ in chunk_frames(path)]


def case_info_nodes():
    # A stream in nodes: their count and the NODE chunk's size; a stream without, 0.
    path = os.path.join(SEAMED, "vectors", "terrain-nodes.pmz")
    j = info_json(path)
    table = sum(size for t, size in chunk_frames(path) if t == 6)
    check(j["nodes"] == 32 and j["node_table_bytes"] == table > 0,
          f"terrain-nodes.pmz: nodes {j['nodes']}, table {j['node_table_bytes']} (NODE: {table})")
    o = run([tool("pmz-info"), path]).stdout.decode()
    check(f"nodes     32, decodable independently once their parents are (table {table} bytes)"
          in o, f"pmz-info terrain-nodes.pmz: {o}")
    j = info_json(SAMPLE_PMZ)
    check(j["nodes"] == 0 and j["node_table_bytes"] == 0 and "nodes " not in
          run([tool("pmz-info"), SAMPLE_PMZ]).stdout.decode(), f"sample.pmz: {j}")


def case_decode_view():
    # --camera: the nodes a view needs, read by ranges. Seeing the whole grid at a tiny error
    # gives the whole stream's bytes; a close view of a corner reads less and writes fewer faces.
    d = fresh("view")
    pmz = bumpy_grid_pmz(d)
    whole, every, corner = (os.path.join(d, f"{x}.ply") for x in ("whole", "every", "corner"))
    r = run([tool("pmz-decode"), pmz, "-o", whole])
    check(r.returncode == 0, f"pmz-decode: {err_text(r)}")
    r = run([tool("pmz-decode"), pmz, "-o", every, "--camera", "31,31,300,31,31,0",
             "--pixel-error", "0"])
    check(r.returncode == 0, f"pmz-decode --camera (all): {err_text(r)}")
    with open(whole, "rb") as a, open(every, "rb") as b:
        check(a.read() == b.read(), "a view of every node wrote other bytes than the stream")
    r = run([tool("pmz-decode"), pmz, "-o", corner, "--camera", "8,8,6,8,8,0", "--size",
             "640x480"])
    m = re.search(r"(\d+) faces.*read (\d+) of (\d+) bytes", err_text(r))
    check(r.returncode == 0 and m, f"pmz-decode --camera (corner): {err_text(r)}")
    full = info_json(pmz)["full_faces"]
    check(int(m.group(1)) < full and int(m.group(2)) < int(m.group(3)),
          f"a close view of a corner: {err_text(r)}")
    for bad in (["--camera", "1,2,3"], ["--camera", "0,0,1,0,0,0", "--size", "big"]):
        r = run([tool("pmz-decode"), pmz, "-o", corner] + bad)
        check(r.returncode == 2 and "--" in err_text(r), f"{bad}: {err_text(r)}")


def case_decode_view_face_budget():
    # --max-faces with --camera: the mesh written has at most N faces, from fewer nodes than
    # without the budget; --help shows the option with its default (0: no budget).
    d = fresh("view_budget")
    pmz = bumpy_grid_pmz(d)
    camera = ["--camera", "8,8,6,8,8,0", "--size", "640x480", "--pixel-error", "0.5"]
    summary = r"(\d+) faces.* (\d+) of \d+ nodes"
    free, tight = (os.path.join(d, f"{x}.ply") for x in ("free", "tight"))
    r = run([tool("pmz-decode"), pmz, "-o", free] + camera)
    m = re.search(summary, err_text(r))
    check(r.returncode == 0 and m, f"pmz-decode --camera: {err_text(r)}")
    faces, nodes = int(m.group(1)), int(m.group(2))
    budget = faces // 2
    r = run([tool("pmz-decode"), pmz, "-o", tight, "--max-faces", str(budget)] + camera)
    m = re.search(summary, err_text(r))
    check(r.returncode == 0 and m, f"pmz-decode --camera --max-faces: {err_text(r)}")
    with open(tight, "rb") as f:
        header = f.read(4096).split(b"end_header")[0].decode(errors="replace")
    written = re.search(r"element face (\d+)", header)
    check(written and int(written.group(1)) == int(m.group(1)) and
          info_json(pmz)["base_faces"] < int(m.group(1)) <= budget and 1 < int(m.group(2)) < nodes,
          f"--max-faces {budget} ({faces} faces from {nodes} nodes without): {err_text(r)}")
    r = run([tool("pmz-decode"), pmz, "-o", tight, "--max-faces", "10"])
    check(r.returncode == 2 and "--camera" in err_text(r), f"--max-faces alone: {err_text(r)}")
    h = run([tool("pmz-decode"), "--help"]).stdout.decode()
    line = next((l for l in h.splitlines() if "--max-faces" in l), "")
    check("=0" in line, f"pmz-decode --help: --max-faces without its default: {line!r}")


def case_encode_nodes_by_default():
    # --cluster-vertices auto: a mesh of at least 65,536 vertices is written in nodes, a smaller
    # one as one node; either decodes to its full face count.
    d = fresh("encode_nodes")
    for faces, nodes in ((140000, True), (120000, False)):
        ply, pmz, out = (os.path.join(d, f"t{faces}.{e}") for e in ("ply", "pmz", "obj"))
        r = run([tool("pmz-generate"), "--faces", str(faces), "-o", ply, "-q"])
        check(r.returncode == 0, f"pmz-generate: {err_text(r)}")
        r = run([tool("pmz-encode"), ply, "-o", pmz, "-q"])
        check(r.returncode == 0, f"pmz-encode {ply}: {err_text(r)}")
        j = info_json(pmz)
        check((j["full_vertices"] >= 65536) == nodes and (j["nodes"] > 1) == nodes,
              f"{faces} faces: {j['full_vertices']} vertices, {j['nodes']} nodes")
        r = run([tool("pmz-decode"), pmz, "-o", out])
        check(r.returncode == 0 and f"{j['full_faces']} faces" in err_text(r),
              f"pmz-decode {pmz}: {err_text(r)}")


def case_encode_plan_tasks_assemble():
    # pmz-encode --plan / --task / --assemble: the tasks run by GNU parallel as separate
    # processes, then the assembled stream is the one-process encode's bytes; a missing task's
    # result is named, exit 1, nothing written; a task run twice writes the same result.
    check(shutil.which("parallel"), "GNU parallel is not installed (README.md, set-up)")
    d = fresh("encode_plan")
    ply, plan, one, out = (os.path.join(d, n) for n in ("t.ply", "plan", "one.pmz", "out.pmz"))
    r = run([tool("pmz-generate"), "--faces", "140000", "-o", ply, "-q"])
    check(r.returncode == 0, f"pmz-generate: {err_text(r)}")
    opts = ["--cluster-vertices", "4096", "--position-bits", "12"]
    r = run([tool("pmz-encode"), ply, "--plan", plan] + opts)
    check(r.returncode == 0, f"--plan: {err_text(r)}")
    with open(os.path.join(plan, "tasks")) as f:
        ids = f.read().split()
    check(len(ids) > 4 and ids == [str(i) for i in range(len(ids))], f"tasks: {ids}")
    r = run([tool("pmz-encode"), "--assemble", plan, "-o", out])
    lines = err_text(r).strip().splitlines()
    check(r.returncode == 1 and len(lines) == 1 and os.path.join(plan, "0.cell") in lines[0]
          and "missing" in lines[0] and not os.path.exists(out),
          f"assemble without results: rc={r.returncode} {lines}")
    r = run([tool("pmz-encode"), "--task", plan, "0", "--metric", "qem"])
    check(r.returncode == 2 and "--metric" in err_text(r), f"--task with an option: {err_text(r)}")
    r = run([tool("pmz-encode"), "--task", plan, "0"])
    check(r.returncode == 0, f"--task of the first cell: {err_text(r)}")
    with open(os.path.join(plan, "0.cell"), "rb") as f:
        first = f.read()
    r = run(["parallel", "--will-cite", "-j", "2", tool("pmz-encode"), "--task", plan, "{}",
             "::::", os.path.join(plan, "tasks")], timeout=300)
    check(r.returncode == 0, f"parallel --task: {err_text(r)}")
    with open(os.path.join(plan, "0.cell"), "rb") as f:
        check(f.read() == first, "the first cell run twice wrote different results")
    check(sorted(os.listdir(plan)) == sorted(["mesh", "options", "tasks"] +
                                             [i + ".cell" for i in ids] +
                                             [i + ".region" for i in ids]),
          f"the plan holds more: {sorted(os.listdir(plan))}")
    r = run([tool("pmz-encode"), "--assemble", plan, "-o", out])
    check(r.returncode == 0, f"--assemble: {err_text(r)}")
    r = run([tool("pmz-encode"), ply, "-o", one, "-q"] + opts)
    check(r.returncode == 0, f"pmz-encode {ply}: {err_text(r)}")
    r = run(["cmp", one, out])
    check(r.returncode == 0, f"assembled and one-process streams differ: {r.stdout}")
    check(info_json(out)["nodes"] > len(ids), "the stream has no more nodes than cells")


def peak_kb(args):
    """Runs args; (exit status, its peak resident set in KB). Measured by GNU time, which forks
    the command from its own small image: a child of this process would report at least this
    process's own peak (Linux keeps the largest resident set across fork and exec)."""
    check(os.path.exists("/usr/bin/time"), "/usr/bin/time is not installed (README.md, set-up)")
    report = os.path.join(WORK, "peak.txt")
    r = subprocess.run(["/usr/bin/time", "-f", "%M", "-o", report] + args,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(report) as f:
        lines = f.read().split()
    check(lines and lines[-1].isdigit(), f"/usr/bin/time wrote no peak for {args[0]}")
    return r.returncode, int(lines[-1])


def sanitized(binary):
    """Whether binary was built with AddressSanitizer (its memory is then not the program's)."""
    with open(binary, "rb") as f:
        return b"__asan_init" in f.read()


def case_encode_memory_budget():
    # --memory: an input whose encode needs more than the budget is refused once read (one line
    # naming it, exit 1, nothing written, no plan); the estimate it states lies below the
    # encode's measured peak and not far below; encodes run at once with -j share the budget
    # (two that do not fit together run one after the other: the process peaks as one does);
    # a size that is not one is a usage error; a task of a plan takes --memory. Under
    # AddressSanitizer (shadow memory, freed blocks held in quarantine) the peaks are not the
    # program's: only the release build's are compared.
    measured = not sanitized(tool("pmz-encode"))
    d = fresh("encode_memory")
    ply, ply2, out = (os.path.join(d, n) for n in ("t.ply", "u.ply", "t.pmz"))
    r = run([tool("pmz-generate"), "--faces", "300000", "-o", ply, "-q"])
    check(r.returncode == 0, f"pmz-generate: {err_text(r)}")
    shutil.copy(ply, ply2)
    rc, single = peak_kb([tool("pmz-encode"), ply, "-o", out, "-q", "--memory", "0"])
    check(rc == 0, f"pmz-encode --memory 0: rc={rc}")
    os.remove(out)
    r = run([tool("pmz-encode"), ply, "-o", out, "-q", "--memory", "1M"])
    lines = err_text(r).strip().splitlines()
    check(r.returncode == 1 and len(lines) == 1 and ply in lines[0]
          and "more than the budget of 1.00 MB (--memory)" in lines[0]
          and sorted(os.listdir(d)) == ["t.ply", "u.ply"], f"--memory 1M: rc={r.returncode} {lines}")
    m = re.search(r"needs about ([0-9.]+) (KB|MB|GB)", lines[0])
    check(m, f"no estimate in: {lines[0]}")
    estimate = float(m.group(1)) * {"KB": 1, "MB": 1024, "GB": 1024 * 1024}[m.group(2)]
    check(not measured or 0.5 * single <= estimate <= single,
          f"estimate {estimate:.0f} KB against a measured peak of {single} KB")
    for size in ("12Q", "1.5", "-3G", ""):
        r = run([tool("pmz-encode"), ply, "-o", out, "--memory", size])
        check(r.returncode == 2 and "--memory" in err_text(r), f"--memory '{size}': {err_text(r)}")
    both = ["--out-dir", os.path.join(d, "out"), "-j", "2", "-q"]
    rc, unbounded = peak_kb([tool("pmz-encode"), ply, ply2] + both + ["--memory", "0"])
    check(rc == 0 and (not measured or unbounded > 1.7 * single),
          f"-j 2 unbounded: rc={rc}, peak {unbounded} KB against {single} KB for one")
    budget = f"{int(estimate * 1.5)}k"
    rc, shared = peak_kb([tool("pmz-encode"), ply, ply2] + both + ["--memory", budget])
    check(rc == 0 and (not measured or shared < 1.4 * single),
          f"-j 2 within {budget}: rc={rc}, peak {shared} KB against {single} KB for one")
    check(sorted(os.listdir(os.path.join(d, "out"))) == ["t.pmz", "u.pmz"], "-j 2 outputs")
    plan = os.path.join(d, "plan")
    r = run([tool("pmz-encode"), ply, "--plan", plan, "--memory", "1M"])
    check(r.returncode == 1 and "(--memory)" in err_text(r)
          and not os.path.exists(os.path.join(plan, "tasks")), f"--plan over the budget: {err_text(r)}")
    r = run([tool("pmz-encode"), ply, "--plan", plan, "--memory", "1.5G"])
    check(r.returncode == 0, f"--plan: {err_text(r)}")
    r = run([tool("pmz-encode"), "--task", plan, "0", "--memory", "512MB"])
    check(r.returncode == 0, f"--task with --memory: {err_text(r)}")


def case_encode_task_reads_its_region():
    # A task of a plan reads its cell's region, not the mesh: it runs with the plan's mesh file
    # gone, in a fraction of the memory of the plan (which holds the whole mesh), and writes
    # the result a task reading the whole mesh writes (a plan without regions: the tasks of a
    # mesh with attributes). A damaged region: one line naming it, exit 1, no result.
    d = fresh("encode_region")
    ply, plan, bare = (os.path.join(d, n) for n in ("t.ply", "plan", "bare"))
    r = run([tool("pmz-generate"), "--faces", "300000", "-o", ply, "-q"])
    check(r.returncode == 0, f"pmz-generate: {err_text(r)}")
    rc, plan_kb = peak_kb([tool("pmz-encode"), ply, "--plan", plan, "--cluster-vertices", "4096"])
    check(rc == 0, f"--plan: exit {rc}")
    shutil.copytree(plan, bare)
    for name in os.listdir(bare):
        if name.endswith(".region"):
            os.remove(os.path.join(bare, name))
    os.rename(os.path.join(plan, "mesh"), os.path.join(d, "mesh"))
    rc, task_kb = peak_kb([tool("pmz-encode"), "--task", plan, "5"])
    check(rc == 0, f"the task of cell 5 without the mesh: exit {rc}")
    # (A quarter; under AddressSanitizer, whose shadow memory weighs more on the small task,
    # 40%: 14.7 MB against 88 MB, and 69 MB against 220 MB.)
    share = 0.4 if sanitized(tool("pmz-encode")) else 0.25
    check(task_kb < share * plan_kb, f"a task took {task_kb} KB, the plan {plan_kb} KB")
    r = run([tool("pmz-encode"), "--task", bare, "5"])
    check(r.returncode == 0, f"the task of cell 5 on the whole mesh: {err_text(r)}")
    with open(os.path.join(plan, "5.cell"), "rb") as a, open(os.path.join(bare, "5.cell"), "rb") as b:
        check(a.read() == b.read(), "the region's result differs from the whole mesh's")
    region = os.path.join(plan, "6.region")
    data = open(region, "rb").read()
    for cut in (data[:len(data) // 2], data[:20], data[:-1], b"PMZREGN1" + b"\xff" * 64):
        open(region, "wb").write(cut)
        r = run([tool("pmz-encode"), "--task", plan, "6"])
        lines = err_text(r).strip().splitlines()
        check(r.returncode == 1 and len(lines) == 1 and region in lines[0] and
              not os.path.exists(os.path.join(plan, "6.cell")),
              f"a damaged region: rc={r.returncode} {lines}")
    os.rename(os.path.join(plan, "5.region"), region)
    r = run([tool("pmz-encode"), "--task", plan, "6"])
    check(r.returncode == 1 and "the region of cell 5, not of cell 6" in err_text(r),
          f"another cell's region: rc={r.returncode} {err_text(r)}")
    # With texture coordinates, normals and materials: the tasks from regions assemble to the
    # one-process encode's bytes.
    obj, splan, one, out = (os.path.join(d, n) for n in ("s.obj", "splan", "one.pmz", "out.pmz"))
    for name in ("seamed.obj", "seamed.mtl"):
        shutil.copy(os.path.join(SEAMED, "meshes", name), d)
    os.rename(os.path.join(d, "seamed.obj"), obj)
    opts = ["--cluster-vertices", "24"]
    r = run([tool("pmz-encode"), obj, "--plan", splan] + opts)
    check(r.returncode == 0, f"--plan {obj}: {err_text(r)}")
    ids = open(os.path.join(splan, "tasks")).read().split()
    check(len(ids) > 2 and all(os.path.exists(os.path.join(splan, i + ".region")) for i in ids),
          f"{obj}: tasks {ids}, {sorted(os.listdir(splan))}")
    os.rename(os.path.join(splan, "mesh"), os.path.join(d, "smesh"))  # the tasks do without
    for i in ids:
        r = run([tool("pmz-encode"), "--task", splan, i])
        check(r.returncode == 0, f"--task {i} of {obj}: {err_text(r)}")
    os.rename(os.path.join(d, "smesh"), os.path.join(splan, "mesh"))
    r = run([tool("pmz-encode"), "--assemble", splan, "-o", out])
    check(r.returncode == 0, f"--assemble {obj}: {err_text(r)}")
    r = run([tool("pmz-encode"), obj, "-o", one, "-q"] + opts)
    check(r.returncode == 0 and run(["cmp", one, out]).returncode == 0,
          f"{obj}: the assembled stream is not the one-process encode's")


# The arrays of a cell's region in their order (EngineData::for_each_array in
# encoder/src/simplify.cpp) and the bytes of one element of each.
REGION_ARRAYS = [("pos", 4), ("vert", 4), ("twin", 4), ("out", 4), ("face_terms", 32),
                 ("vertex_terms", 32), ("quadric", 80), ("accumulated", 80), ("self_error", 8),
                 ("witness", 4), ("wedge", 4), ("material", 4), ("values", 4), ("target", 4),
                 ("stale", 1), ("cell", 8), ("key", 4), ("inner", 1), ("region_bound", 4)]
ELEMENT = {1: "B", 4: "I", 8: "Q"}


class Region:
    """A cell's region (CellRegion in encoder/src/simplify.cpp) as bytes to damage: its vertex
    and face lists, the cell's vertices (region numbers), and per array where it starts."""

    def __init__(self, data):
        self.data = bytearray(data)
        p = 8 + struct.calcsize("<IIQQdBB9fddBBBIdd")  # the magic, the cell and the settings
        lists = []
        for _ in range(4):
            (n,) = struct.unpack_from("<I", data, p)
            lists.append(struct.unpack_from(f"<{n}I", data, p + 4))
            p += 4 + 4 * n
        self.vertices, self.faces, _, self.members = lists
        self.at = {}
        for name, size in REGION_ARRAYS:
            (local,) = struct.unpack_from("<Q", data, p + 8)
            self.at[name] = (p + 16, size)
            p += 16 + local * size
        check(p == len(data), f"the region's layout: {p} bytes of {len(data)}")

    def get(self, name, i, fmt=None):
        start, size = self.at[name]
        return struct.unpack_from("<" + (fmt or ELEMENT[size]), self.data, start + i * size)[0]

    def set(self, name, i, value, fmt=None):
        start, size = self.at[name]
        struct.pack_into("<" + (fmt or ELEMENT[size]), self.data, start + i * size, value)


def case_encode_task_refuses_broken_engine_state():
    # A region whose counts and ids are in range and whose half-edges pair up, but whose engine
    # state breaks a rule a cell's run relies on (fuzz_region found such regions crashing the
    # engine): one line naming the region and the rule, exit 1, no result. Each damage is one
    # rule broken in a real region: the corner cell of a 12 x 12 grid (boundary vertices), the
    # same under QEM (no face and vertex terms), a cell of the seamed mesh (attribute wedges).
    d = fresh("encode_broken_region")
    off, obj = os.path.join(d, "grid.off"), os.path.join(d, "s.obj")
    n = 12
    with open(off, "w") as f:
        f.write(f"OFF\n{(n + 1) ** 2} {2 * n * n} 0\n")
        for y in range(n + 1):
            for x in range(n + 1):
                f.write(f"{x / n} {y / n} {0.2 * math.sin(x) * math.cos(y):.6f}\n")
        for y in range(n):
            for x in range(n):
                a = y * (n + 1) + x
                f.write(f"3 {a} {a + 1} {a + n + 2}\n3 {a} {a + n + 2} {a + n + 1}\n")
    for name in ("seamed.obj", "seamed.mtl"):
        shutil.copy(os.path.join(SEAMED, "meshes", name), d)
    os.rename(os.path.join(d, "seamed.obj"), obj)

    def first_region(name, mesh, args):
        """The plan's folder and its region of cell 0, which runs as it is."""
        plan = os.path.join(d, name)
        r = run([tool("pmz-encode"), mesh, "--plan", plan, "-q"] + args)
        check(r.returncode == 0, f"--plan {args}: {err_text(r)}")
        r = run([tool("pmz-encode"), "--task", plan, "0"])
        check(r.returncode == 0, f"the undamaged region of {name}: {err_text(r)}")
        os.remove(os.path.join(plan, "0.cell"))
        with open(os.path.join(plan, "0.region"), "rb") as f:
            return plan, f.read()

    def refused(plan, good, damage, reason):
        r = Region(good)
        damage(r)
        region = os.path.join(plan, "0.region")
        with open(region, "wb") as f:
            f.write(r.data)
        r = run([tool("pmz-encode"), "--task", plan, "0"])
        lines = err_text(r).strip().splitlines()
        check(r.returncode == 1 and len(lines) == 1 and region in lines[0] and
              reason in lines[0] and not os.path.exists(os.path.join(plan, "0.cell")),
              f"a region damaged ({reason}): rc={r.returncode} {lines}")

    plan, good = first_region("plan", off, ["--cluster-vertices", "16"])
    g = Region(good)
    members = g.members
    kboundary = 8  # the engine's flag: the vertex is on the boundary
    b = next(v for v in members if g.get("stale", v) & kboundary)
    leaving = [h for h in range(4 * len(g.faces)) if h % 4 != 3 and g.get("vert", h) == b]
    check(len(leaving) > 1, f"vertex {b} has one face")
    inside = next(v for v in range(len(g.vertices)) if v not in members)
    # A live face with twins on its last two edges, not its third corner's out-edge.
    face = next(f for f in range(len(g.faces))
                if g.get("vert", 4 * f) != 0xFFFFFFFF and
                all(g.get("twin", 4 * f + k) < 0xFFFFFFF0 for k in (1, 2)) and
                g.get("out", g.get("vert", 4 * f + 2)) != 4 * f + 2)

    def repeat_corner(r):
        # Face (a, b, c) made (a, b, b), the twins of its last two edges and theirs cut so that
        # the half-edges still pair up.
        r.set("vert", 4 * face + 2, r.get("vert", 4 * face + 1))
        for k in (1, 2):
            r.set("twin", r.get("twin", 4 * face + k), 0xFFFFFFFF)
            r.set("twin", 4 * face + k, 0xFFFFFFFF)

    for reason, damage in [
        ("flagged on the boundary", lambda r: r.set("stale", b, r.get("stale", b) & ~kboundary)),
        ("not one fan", lambda r: r.set("out", b, next(h for h in leaving
                                                       if h != r.get("out", b)))),
        ("not the cell of its vertices",
         lambda r: r.set("cell", inside, r.get("cell", members[0]))),
        ("flags are out of range",
         lambda r: r.set("stale", members[0], r.get("stale", members[0]) | 128)),
        ("repeats a corner", repeat_corner),
        ("not finite", lambda r: r.set("quadric", members[0], float("inf"), "d")),
    ]:
        refused(plan, good, damage, reason)
    # Under QEM: a vertex flagged to recompute its torsion (1) or its key (2) from the terms QEM
    # does not keep.
    plan, good = first_region("qplan", off, ["--cluster-vertices", "16", "--metric", "qem"])
    for flag in (1, 2):
        refused(plan, good, lambda r: r.set("stale", r.members[0],
                                            r.get("stale", r.members[0]) | flag),
                "torsion or key is flagged stale")
    # With attribute wedges: a live corner's wedge made one outside the region.
    plan, good = first_region("splan", obj, ["--cluster-vertices", "24"])
    refused(plan, good, lambda r: r.set("wedge", next(
        h for h in range(4 * len(r.faces)) if h % 4 != 3 and r.get("vert", h) != 0xFFFFFFFF),
        0xFFFFFFFE), "without an attribute wedge")


def case_info_texcoords_only():
    d = fresh("info_texcoords")
    obj = os.path.join(d, "uv.obj")
    with open(os.path.join(SEAMED, "meshes", "seamed.obj")) as src, open(obj, "w") as out:
        for line in src:
            w = line.split()
            if not w or w[0] in ("vn", "mtllib", "usemtl"):
                continue
            if w[0] == "v":
                line = " ".join(w[:4]) + "\n"  # without the colour
            elif w[0] == "f":
                line = "f " + " ".join("/".join(c.split("/")[:2]) for c in w[1:]) + "\n"
            out.write(line)
    pmz = os.path.join(d, "uv.pmz")
    r = run([tool("pmz-encode"), obj, "-o", pmz])
    check(r.returncode == 0, f"pmz-encode {obj}: rc={r.returncode} {err_text(r)}")
    j = info_json(pmz)
    a = attribute_bytes_add_up(j, "texture coordinates only")
    check(sorted(a) == ["framing", "texcoords", "wedges"] and a["texcoords"]["bits"] == 12 and
          a["texcoords"]["bytes"] > 0, f"texture coordinates only: {a}")
    o = run([tool("pmz-info"), pmz]).stdout.decode()
    check("texture coordinates" in o and "normals" not in o and "colours" not in o,
          f"pmz-info on texture coordinates only: {o}")
    # Cut before the first ATTR chunk: the kinds HEAD declares are still named.
    data = open(pmz, "rb").read()
    cut = os.path.join(d, "cut.pmz")
    open(cut, "wb").write(data[:j["header_bytes"] + 2])
    o = run([tool("pmz-info"), cut]).stdout.decode()
    check("texture coordinates  1 set, 12 bits" in o and "none in the file" in o,
          f"pmz-info on a file cut before ATTR: {o}")


def case_info_attribute_damage():
    # The last ATTR chunk's second half set to 0xFF, its CRC made right: the framing reads, the
    # symbols do not. Counting the attribute bytes applies the splits, which finds it.
    d = fresh("info_attr_damage")
    b = bytearray(open(os.path.join(SEAMED, "vectors", "seamed-q.pmz"), "rb").read())

    def varint(p):
        v = s = 0
        while True:
            v |= (b[p] & 0x7F) << s
            s += 7
            p += 1
            if b[p - 1] < 0x80:
                return v, p
    at, last = 8, None
    while b[at] != 4:  # up to END
        size, q = varint(at + 1)
        if b[at] == 5:
            last = (at, q, size)
        at = q + 4 + size
    at, q, size = last
    p = q + 4
    b[p + size // 2:p + size] = b"\xff" * (size - size // 2)
    b[q:q + 4] = zlib.crc32(bytes(b[at:q]) + bytes(b[p:p + size])).to_bytes(4, "little")
    path = os.path.join(d, "damaged.pmz")
    open(path, "wb").write(b)
    r = run([tool("pmz-info"), path])
    e = err_text(r)
    check(r.returncode == 1 and r.stdout == b"" and "attributes malformed" in e and
          e.count("\n") == 1, f"pmz-info on damaged attributes: rc={r.returncode} {e!r}")


def case_unreachable_decode_target_warns():
    d = fresh("target")
    out = os.path.join(d, "o.obj")
    whole = info_json(SAMPLE_PMZ)
    r = run([tool("pmz-decode"), SAMPLE_PMZ, "-o", out, "--faces", "100000000"])
    e = err_text(r)
    check(r.returncode == 0 and "warning" in e and "100000000 faces" in e and
          str(whole["full_faces"]) in e,
          f"--faces beyond the file: expected a warning saying what was written: {e!r}")
    r = run([tool("pmz-decode"), SAMPLE_PMZ, "-o", out, "--bytes", "300", "--faces",
             str(whole["full_faces"])])
    e = err_text(r)
    check(r.returncode == 0 and "warning" in e and "first 300 bytes" in e,
          f"--faces beyond what --bytes holds: expected a warning: {e!r}")
    r = run([tool("pmz-decode"), SAMPLE_PMZ, "-o", out, "--faces", "1"])
    check("warning" not in err_text(r), f"a reachable target warned: {err_text(r)!r}")


def faces_in_obj(path):
    return sum(1 for l in open(path) if l.startswith("f "))


def case_zero_is_the_base_mesh():
    d = fresh("zero")
    base = info_json(SAMPLE_PMZ)["base_faces"]
    for opt in ("--faces", "--ratio"):
        out = os.path.join(d, "z.obj")
        r = run([tool("pmz-decode"), SAMPLE_PMZ, "-o", out, opt, "0"])
        check(r.returncode == 0 and faces_in_obj(out) == base,
              f"pmz-decode {opt} 0: expected the base mesh ({base} faces)")
    view = tool("pmz-view")
    if not os.path.exists(view) or not shutil.which("xvfb-run"):
        print("  (pmz-view part skipped: no pmz-view or no xvfb-run)")
        return
    for opt in ("--faces", "--ratio"):
        png = os.path.join(d, "z.png")
        r = run(["xvfb-run", "-a", view, SAMPLE_PMZ, "--screenshot", png, "--size", "64x64",
                 opt, "0"])
        o = r.stdout.decode()
        check(r.returncode == 0 and f": {base} faces" in o,
              f"pmz-view {opt} 0: expected the base mesh ({base} faces): rc={r.returncode} {o!r} "
              f"{err_text(r)}")


# ---- decoding threads ----


def bumpy_grid_pmz(d):
    # A bumpy grid in cells of 200 vertices: a stream whose levels hold several nodes each.
    n = 64
    mesh = os.path.join(d, "grid.off")
    with open(mesh, "w") as f:
        f.write(f"OFF\n{n * n} {2 * (n - 1) * (n - 1)} 0\n")
        for y in range(n):
            for x in range(n):
                f.write(f"{x} {y} {((x * 7919 + y * 104729) % 13) / 4}\n")
        for y in range(n - 1):
            for x in range(n - 1):
                a = y * n + x
                f.write(f"3 {a} {a + 1} {a + n + 1}\n3 {a} {a + n + 1} {a + n}\n")
    pmz = os.path.join(d, "grid.pmz")
    r = run([tool("pmz-encode"), mesh, "--cluster-vertices", "200", "-o", pmz])
    check(r.returncode == 0, f"pmz-encode --cluster-vertices: {err_text(r)}")
    check(6 in chunk_types(pmz) and info_json(pmz)["split_chunks"] > 8,
          "expected a NODE chunk (type 6) and many nodes' SPLT chunks")
    return pmz


def case_decode_threads_same_bytes():
    d = fresh("threads")
    pmz = bumpy_grid_pmz(d)
    outs = {}
    for t in ("1", "2", "3", "0"):
        for target in ([], ["--ratio", "0.6"]):
            out = os.path.join(d, f"t{t}{len(target)}.ply")
            r = run([tool("pmz-decode"), pmz, "-o", out, "--threads", t] + target)
            check(r.returncode == 0, f"pmz-decode --threads {t}: {err_text(r)}")
            with open(out, "rb") as f:
                outs[(t, len(target))] = f.read()
    for key, data in outs.items():
        check(data == outs[("1", key[1])], f"pmz-decode --threads {key[0]} wrote other bytes")


# ---- batch encoding ----

def case_batch_encoding():
    d = fresh("batch")
    inputs = []
    for i in range(3):
        p = os.path.join(d, f"m{i}.obj")
        shutil.copy(SAMPLE_OBJ, p)
        inputs.append(p)
    bad = os.path.join(d, "bad.obj")
    open(bad, "w").write("v 0 0 0\nf 1 2 3\n")
    out = os.path.join(d, "out")
    os.makedirs(out)
    r = run([tool("pmz-encode")] + inputs[:1] + [bad] + inputs[1:] + ["--out-dir", out, "-j", "2"])
    lines = r.stdout.decode().splitlines()
    check(r.returncode == 1, f"a batch with a failing asset: expected exit 1, got {r.returncode}")
    check(sorted(os.listdir(out)) == ["m0.pmz", "m1.pmz", "m2.pmz"],
          f"the other assets were not all written: {os.listdir(out)}")
    check(len(lines) == 3 and all(".pmz: " in l for l in lines),
          f"expected one line per encoded asset: {lines}")
    check(f"pmz-encode: {bad}" in err_text(r), f"the failing asset is not named: {err_text(r)}")
    ref = os.path.join(d, "ref.pmz")
    run([tool("pmz-encode"), SAMPLE_OBJ, "-o", ref])
    for f in os.listdir(out):
        check(open(os.path.join(out, f), "rb").read() == open(ref, "rb").read(),
              f"{f} differs from a single encode")
    shutil.rmtree(out)
    os.makedirs(out)
    r = run([tool("pmz-encode")] + inputs + ["--out-dir", out])
    check(r.returncode == 0 and len(r.stdout.decode().splitlines()) == 3,
          f"an all-good batch (default -j): rc={r.returncode} {err_text(r)}")
    os.makedirs(os.path.join(d, "sub"))
    twin = os.path.join(d, "sub", "m0.obj")
    shutil.copy(SAMPLE_OBJ, twin)
    r = run([tool("pmz-encode"), inputs[0], twin, "--out-dir", out])
    check(r.returncode == 2, f"two inputs writing the same output: expected exit 2, got "
          f"{r.returncode}")
    # --out-dir makes a missing folder with its parents (as mkdir -p), but not on a usage error,
    # and refuses a path that is not a folder.
    nested = os.path.join(d, "new", "deeper")
    r = run([tool("pmz-encode")] + inputs[:2] + ["--out-dir", nested])
    check(r.returncode == 0 and sorted(os.listdir(nested)) == ["m0.pmz", "m1.pmz"],
          f"--out-dir with a missing folder: rc={r.returncode} {err_text(r)}")
    never = os.path.join(d, "never")
    r = run([tool("pmz-encode"), inputs[0], twin, "--out-dir", never])
    check(r.returncode == 2 and not os.path.exists(never),
          f"a usage error made the --out-dir folder: rc={r.returncode}")
    r = run([tool("pmz-encode")] + inputs[:2] + ["--out-dir", ref])
    check(r.returncode == 1 and f"pmz-encode: {ref}: not a folder" in err_text(r),
          f"--out-dir naming a file: rc={r.returncode} {err_text(r)}")



# ---- mesh formats: one list, one output rule, every writer writes them all ----

# What meshio reads and writes (pmz/mesh_file_formats.hpp), as a user sees it.
READ_FORMATS = ["obj", "off", "ply", "stl", "gltf", "glb"]
WRITTEN_FORMATS = ["obj", "off", "ply", "stl", "glb"]
MESH_READERS = ["pmz-encode", "pmz-simplify", "pmz-compare"]
# Each writer's arguments before -o (pmz-simplify halves the sample).
MESH_WRITERS = {"pmz-decode": [SAMPLE_PMZ], "pmz-simplify": [SAMPLE_OBJ, "--ratio", "0.5"]}


def case_output_without_extension_takes_format():
    d = fresh("no_extension")
    messages = {}
    for name, args in MESH_WRITERS.items():
        r = run([tool(name)] + args + ["-o", "/dev/null", "--format", "obj"])
        check(r.returncode == 0, f"{name} -o /dev/null --format obj: rc={r.returncode} "
              f"{err_text(r)}")
        out = os.path.join(d, name + "-plain")
        r = run([tool(name)] + args + ["-o", out, "--format", "ply"])
        check(r.returncode == 0 and open(out, "rb").read().startswith(b"ply\n"),
              f"{name} -o NAME --format ply: no PLY written: rc={r.returncode} {err_text(r)}")
        for output in ["/dev/null", "-", os.path.join(d, "plain")]:
            r = run([tool(name)] + args + ["-o", output])
            e = err_text(r)
            check(r.returncode == 2 and e.count("\n") == 1 and e.startswith(name + ": ") and
                  "--format " + "|".join(WRITTEN_FORMATS) in e,
                  f"{name} -o {output} without --format: expected exit 2 and one line naming "
                  f"--format and the formats written, got {r.returncode}: {e!r}")
            messages.setdefault(output, set()).add(e[len(name) + 2:])
    check(not os.path.exists(os.path.join(d, "plain")), "a refused output was written")
    for output, texts in messages.items():
        check(len(texts) == 1, f"-o {output}: the tools word the same rule differently: {texts}")


def case_every_writer_writes_every_format():
    d = fresh("all_formats")
    magic = {"obj": b"v ", "off": b"OFF", "ply": b"ply\n", "glb": b"glTF"}
    for name, args in MESH_WRITERS.items():
        for fmt in WRITTEN_FORMATS:
            out = os.path.join(d, f"{name}.{fmt}")
            r = run([tool(name)] + args + ["-o", out])
            check(r.returncode == 0 and os.path.getsize(out) > 0,
                  f"{name} -o x.{fmt}: rc={r.returncode} {err_text(r)}")
            data = open(out, "rb").read()
            check(data.startswith(magic.get(fmt, b"")) and (fmt != "stl" or
                  len(data) == 84 + 50 * int.from_bytes(data[80:84], "little")),
                  f"{name} -o x.{fmt}: not a .{fmt} file")
            r = run([tool(name)] + args + ["-o", "-", "--format", fmt])
            check(r.returncode == 0 and r.stdout == data,
                  f"{name} -o - --format {fmt} to a pipe: rc={r.returncode} {err_text(r)}; "
                  f"{len(r.stdout)} bytes, the file has {len(data)}")
        # Binary data still never goes to a terminal.
        master, slave = pty.openpty()
        p = subprocess.Popen([tool(name)] + args + ["-o", "-", "--format", "glb"], stdout=slave,
                             stderr=subprocess.PIPE)
        os.close(slave)
        _, err = p.communicate(timeout=60)
        seen = read_pty(master)
        os.close(master)
        check(p.returncode == 1 and b"terminal" in err and b"glTF" not in seen,
              f"{name} -o - --format glb on a terminal: expected a refusal, got "
              f"{p.returncode}: {err!r}")


def gltf_json(uri):
    # One triangle: three float positions, then three uint16 indices.
    return {"asset": {"version": "2.0"}, "buffers": [{"byteLength": 42, "uri": uri}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                            {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]},
                          {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0}


def case_gltf_from_stdin():
    import base64
    d = fresh("gltf_stdin")
    glb = os.path.join(d, "s.glb")
    r = run([tool("pmz-decode"), SAMPLE_PMZ, "-o", glb])
    check(r.returncode == 0, f"pmz-decode -o s.glb: rc={r.returncode} {err_text(r)}")
    data = open(glb, "rb").read()
    for name, args in [("pmz-encode", ["-", "--format", "glb", "-o", os.path.join(d, "e.pmz")]),
                       ("pmz-simplify", ["-", "--format", "glb", "--ratio", "0.5", "-o",
                                         os.path.join(d, "s.obj")]),
                       ("pmz-compare", [glb, "-", "--format", "glb"])]:
        r = run([tool(name)] + args, input=data)
        check(r.returncode == 0, f"{name} - --format glb: rc={r.returncode} {err_text(r)}")
    buffer = struct.pack("<9f3H", 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 2)
    embedded = json.dumps(gltf_json("data:application/octet-stream;base64," +
                                    base64.b64encode(buffer).decode())).encode()
    r = run([tool("pmz-compare"), "-", glb, "--format", "gltf", "--samples", "1000"],
            input=embedded)
    check(r.returncode == 0, f"pmz-compare - --format gltf (data: URI): rc={r.returncode} "
          f"{err_text(r)}")
    open(os.path.join(d, "tri.bin"), "wb").write(buffer)
    external = os.path.join(d, "tri.gltf")
    open(external, "w").write(json.dumps(gltf_json("tri.bin")))
    r = run([tool("pmz-compare"), external, glb, "--samples", "1000"])
    check(r.returncode == 0, f"pmz-compare tri.gltf (buffer beside it): rc={r.returncode} "
          f"{err_text(r)}")
    r = run([tool("pmz-compare"), "-", glb, "--format", "gltf"], input=open(external, "rb").read(),
            cwd=d)
    e = err_text(r)
    check(r.returncode == 1 and e.count("\n") == 1 and e.startswith("pmz-compare: stdin: ") and
          "embedded" in e and "tri.bin" in e,
          f"a .gltf on stdin naming a buffer file: expected exit 1 and one line saying only "
          f"embedded buffers are read, got {r.returncode}: {e!r}")


def all_programs():
    names = TOOLS + ["pmz-demo", "pmz-view"]
    return [n for n in names if n in TOOLS or os.path.exists(tool(n))]


def case_version():
    version = os.environ.get("PMZ_PROJECT_VERSION", "")
    check(version, "PMZ_PROJECT_VERSION (the CMake project version) is not set")
    for name in all_programs():
        r = run([tool(name), "--version"])
        check(r.returncode == 0 and r.stdout.decode() == f"{name} {version}\n",
              f"{name} --version: expected exit 0 and '{name} {version}', got {r.returncode}: "
              f"{r.stdout!r} {err_text(r)}")


def case_help_names_the_formats():
    for name in MESH_READERS + ["pmz-view"] + list(MESH_WRITERS):
        if not os.path.exists(tool(name)):
            continue
        h = run([tool(name), "--help"]).stdout.decode()
        wanted = (READ_FORMATS if name in MESH_READERS + ["pmz-view"] else []) + \
                 (WRITTEN_FORMATS if name in MESH_WRITERS else [])
        missing = [f for f in wanted if f".{f}" not in h]
        check(not missing, f"{name} --help does not name {missing}")


CASES = [(n[5:], f) for n, f in sorted(globals().items()) if n.startswith("case_")]


def main():
    os.makedirs(WORK, exist_ok=True)
    failed = []
    for name, f in CASES:
        if ONLY and name not in ONLY:
            continue
        try:
            f()
            print(f"ok    {name}")
        except Failed as e:
            print(f"FAIL  {name}: {e}")
            failed.append(name)
        except Exception as e:  # a crash of the test is a failure of the case too
            print(f"FAIL  {name}: {type(e).__name__}: {e}")
            failed.append(name)
    if failed:
        print(f"{len(failed)} case(s) failed: {' '.join(failed)}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
