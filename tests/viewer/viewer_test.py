#!/usr/bin/env python3
"""pmz-view end-to-end checks under xvfb-run (Mesa's software GL).

  viewer_test.py screenshots --view BIN --encode BIN --workdir DIR
  viewer_test.py streaming   --view BIN --encode BIN --workdir DIR
  viewer_test.py errors      --view BIN --workdir DIR

The first two encode a generated mesh with pmz-encode first. Exit 77 (ctest SKIP) when xvfb-run is
missing. Standard library only: PNGs are decoded here with zlib.
"""
import argparse
import functools
import http.server
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import threading
import time
import zlib

SKIP = 77


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def write_bumpy_torus(path, rings=96, segments=48):
    """A torus with ripples: rings * segments * 2 faces, clearly visible at every size."""
    vertices, faces = [], []
    for i in range(rings):
        u = 2 * math.pi * i / rings
        for j in range(segments):
            v = 2 * math.pi * j / segments
            r = 0.35 * (1 + 0.18 * math.sin(5 * u) * math.cos(3 * v))
            vertices.append(((1 + r * math.cos(v)) * math.cos(u), r * math.sin(v), (1 + r * math.cos(v)) * math.sin(u)))
    for i in range(rings):
        for j in range(segments):
            a = i * segments + j
            b = ((i + 1) % rings) * segments + j
            c = ((i + 1) % rings) * segments + (j + 1) % segments
            d = i * segments + (j + 1) % segments
            faces += [(a, d, c), (a, c, b)]
    with open(path, "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(vertices), len(faces)))
        f.writelines("%.6f %.6f %.6f\n" % p for p in vertices)
        f.writelines("3 %d %d %d\n" % t for t in faces)
    return len(faces)


def encode(args):
    os.makedirs(args.workdir, exist_ok=True)
    off = os.path.join(args.workdir, "torus.off")
    pmz = os.path.join(args.workdir, "torus.pmz")
    faces = write_bumpy_torus(off)
    run = subprocess.run([args.encode, off, "-o", pmz], capture_output=True, text=True, timeout=120)
    if run.returncode != 0:
        fail("pmz-encode failed (%d): %s" % (run.returncode, (run.stderr or run.stdout).strip()))
    return pmz, faces


def read_png(path):
    """8-bit RGB or RGBA, non-interlaced (what stb_image_write produces) -> (w, h, channels, rows)."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail(path + " is not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind = data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, color, _, _, interlace = header
    if depth != 8 or color not in (2, 6) or interlace:
        fail("%s: unexpected PNG layout depth=%d color=%d" % (path, depth, color))
    channels = 3 if color == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - channels] if x >= channels else 0
            b = previous[x]
            c = previous[x - channels] if x >= channels else 0
            if kind == 1:
                line[x] = (line[x] + a) & 255
            elif kind == 2:
                line[x] = (line[x] + b) & 255
            elif kind == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        previous = line
    return width, height, channels, rows


def pixels(path):
    width, height, channels, rows = read_png(path)
    return width, height, [tuple(row[x * channels:x * channels + 3]) for row in rows for x in range(width)]


def far(p, q, tolerance=24):
    return max(abs(a - b) for a, b in zip(p, q)) > tolerance


def xvfb(args, command, timeout):
    return subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24"] + command, capture_output=True,
                          text=True, timeout=timeout)


def test_screenshots(args):
    pmz, faces = encode(args)
    shots = {}
    for name, lod in (("low", ["--ratio", "0.01"]), ("full", ["--ratio", "1"])):
        png = os.path.join(args.workdir, name + ".png")
        if os.path.exists(png):
            os.remove(png)
        run = xvfb(args, [args.view, pmz, "--screenshot", png, "--size", "320x240", "--flat"] + lod, 60)
        if run.returncode != 0 or not os.path.exists(png):
            fail("screenshot %s exited %d: %s" % (name, run.returncode, run.stderr.strip()))
        print(run.stdout.strip())
        m = re.search(r"(\d+) faces", run.stdout)
        shots[name] = (int(m.group(1)) if m else -1, pixels(png))
    low_faces, full_faces = shots["low"][0], shots["full"][0]
    if not (0 < low_faces < full_faces):
        fail("expected fewer faces at 1%% than at 100%%: %d vs %d" % (low_faces, full_faces))
    if full_faces != faces:
        fail("100%% should show all %d faces, showed %d" % (faces, full_faces))
    for name, (_, (w, h, px)) in shots.items():
        background = px[0]  # the corners are background: the object is framed with a margin
        covered = sum(far(p, background) for p in px) / len(px)
        print("%s: %.1f%% of %dx%d pixels are not background" % (name, 100 * covered, w, h))
        if covered < 0.05:
            fail("%s screenshot shows too little of the object (%.1f%%)" % (name, 100 * covered))
    low_px, full_px = shots["low"][1][2], shots["full"][1][2]
    differ = sum(far(a, b) for a, b in zip(low_px, full_px)) / len(low_px)
    print("1%% vs 100%%: %.1f%% of pixels differ" % (100 * differ))
    if differ < 0.01:
        fail("the 1%% and 100%% screenshots look the same (%.2f%% differ)" % (100 * differ))
    print("PASS")


class QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def split_chunks(data):
    """Number of SPLT chunks in a .pmz (spec/format.md section 2: u8 type, varint payload_size,
    u32 CRC, payload; SPLT is type 3, END type 4)."""
    pos, count = 8, 0
    while pos < len(data):
        kind, pos, size, shift = data[pos], pos + 1, 0, 0
        while True:
            byte = data[pos]
            pos += 1
            size |= (byte & 0x7F) << shift
            shift += 7
            if not byte & 0x80:
                break
        pos += 4 + size
        count += kind == 3
        if kind == 4:
            break
    return count


def check_stream(name, run, size, faces, seconds, elapsed, chunks):
    """The log of a streamed run: the mesh shows early, refines in steps, ends at full."""
    lines = [line for line in run.stderr.splitlines() if line.startswith("t=")]
    log = [dict((k, float(v)) for k, v in re.findall(r"(\w+)=([\d.]+)", line)) for line in lines]
    print("%s: %d bytes in about %.1f s, %d log lines, %.1f s in all" % (name, size, seconds, len(log), elapsed))
    if run.returncode != 0:
        fail("%s: pmz-view exited %d: %s" % (name, run.returncode, run.stderr.strip()[-500:]))
    shown = [(e["t"], int(e["bytes"]), int(e["faces"])) for e in log if e.get("faces", 0) > 0]
    if not shown:
        fail(name + ": no log line shows a mesh")
    for t, b, f in shown[:: max(1, len(shown) // 12)] + shown[-1:]:
        print("  t=%.2f bytes=%d faces=%d" % (t, b, f))
    first_t, first_bytes, first_faces = shown[0]
    last_t, last_bytes, last_faces = shown[-1]
    if last_faces != faces or last_bytes != size or not lines[-1].endswith("complete"):
        fail("%s: did not end at full resolution: %d/%d faces, %d/%d bytes" % (name, last_faces, faces, last_bytes, size))
    if first_bytes >= size or first_faces >= faces:
        fail("%s: the mesh appeared only once every byte was in (%d bytes, %d faces)" % (name, first_bytes, first_faces))
    if any(b[2] < a[2] for a, b in zip(shown, shown[1:])):
        fail(name + ": the face count went down while following the stream")
    # Each SPLT chunk that arrives is a new level to show; the base may come with the first
    # chunk (one slice of the pipe), so at least one level per chunk.
    levels = len(set(f for _, _, f in shown))
    if chunks < 3:
        fail("%s: the test file has %d SPLT chunks; it needs several to see levels" % (name, chunks))
    if levels < chunks:
        fail("%s: only %d distinct levels of detail seen while streaming %d SPLT chunks" % (name, levels, chunks))
    if last_t - first_t < seconds / 3:
        fail("%s: refinement did not follow the slow arrival (%.2f s from first mesh to full)" % (name, last_t - first_t))
    print("%s: PASS: %d levels from %d to %d faces over %.1f s" % (name, levels, first_faces, last_faces, last_t - first_t))


def test_streaming(args):
    pmz, faces = encode(args)
    size = os.path.getsize(pmz)
    with open(pmz, "rb") as f:
        data = f.read()
    chunks = split_chunks(data)

    # HTTP, throttled by the viewer's --rate.
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0),
                                             functools.partial(QuietHandler, directory=os.path.dirname(pmz)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    url = "http://127.0.0.1:%d/%s" % (server.server_address[1], os.path.basename(pmz))
    seconds = 4.0  # long enough to see several levels, short enough for ctest
    kbps = max(0.5, size / seconds / 1000)
    start = time.monotonic()
    run = xvfb(args, [args.view, url, "--rate", "%.3f" % kbps, "--log", "--exit-when-complete"], 60)
    server.shutdown()
    check_stream("http --rate %.1f" % kbps, run, size, faces, seconds, time.monotonic() - start, chunks)

    # stdin, from a pipe the writer fills slowly (the source itself is slow, no --rate).
    seconds = 3.0
    command = ["xvfb-run", "-a", args.view, "-", "--log", "--exit-when-complete"]
    start = time.monotonic()
    log_path = os.path.join(args.workdir, "stdin.log")
    with open(log_path, "wb") as log:
        viewer = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=log)
        # Hold the bytes back until the viewer is up (X server start-up takes a while), or
        # the pipe would buffer them and deliver a burst.
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and viewer.poll() is None:
            with open(log_path) as progress:
                if "t=" in progress.read():
                    break
            time.sleep(0.05)
        slices = 40
        for k in range(slices):
            try:
                viewer.stdin.write(data[k * size // slices:(k + 1) * size // slices])
                viewer.stdin.flush()
            except BrokenPipeError:
                break  # the viewer died; its log says why
            time.sleep(seconds / slices)
        try:
            viewer.stdin.close()
        except BrokenPipeError:
            pass
        try:
            viewer.wait(timeout=60)
        except subprocess.TimeoutExpired:
            viewer.kill()
            fail("stdin: pmz-view did not exit")
    with open(log_path) as log:
        run = subprocess.CompletedProcess(command, viewer.returncode, "", log.read())
    check_stream("stdin pipe", run, size, faces, seconds, time.monotonic() - start, chunks)


def test_errors(args):
    """Each failure is one line on stderr and a non-zero exit, never a crash or a hang."""
    workdir = args.workdir
    os.makedirs(workdir, exist_ok=True)
    junk = os.path.join(workdir, "junk.pmz")
    with open(junk, "wb") as f:
        f.write(b"this is not a pmz stream at all" * 10)
    env_no_display = dict(os.environ)
    env_no_display.pop("DISPLAY", None)
    env_no_display.pop("WAYLAND_DISPLAY", None)
    cases = [
        ("missing file", [args.view, os.path.join(workdir, "missing.pmz")], None, "cannot open"),
        ("directory", [args.view, workdir], None, "directory"),
        ("no display", [args.view, junk], env_no_display, "no display"),
        ("unreachable URL", ["xvfb-run", "-a", args.view, "http://127.0.0.1:9/none.pmz"], None, "fetch failed"),
        ("not a .pmz", ["xvfb-run", "-a", args.view, junk, "--screenshot", os.path.join(workdir, "x.png")], None,
         "bad stream"),
        ("bad --size", [args.view, junk, "--size", "12"], None, "--size"),
    ]
    for name, command, env, expect in cases:
        run = subprocess.run(command, capture_output=True, text=True, timeout=30, env=env)
        lines = [line for line in run.stderr.splitlines() if line.startswith("pmz-view:")]
        print("%-16s rc=%d %s" % (name, run.returncode, lines[-1] if lines else run.stderr.strip()))
        if run.returncode == 0 or run.returncode >= 128 or len(lines) != 1 or expect not in lines[0]:
            fail("%s: want one 'pmz-view: ...%s...' line and exit 1, got rc=%d stderr=%r" %
                 (name, expect, run.returncode, run.stderr))
    if os.path.exists(os.path.join(workdir, "x.png")):
        fail("a failed screenshot left a file behind")
    print("PASS")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("test", choices=["screenshots", "streaming", "errors"])
    parser.add_argument("--view", required=True)
    parser.add_argument("--encode")
    parser.add_argument("--workdir", required=True)
    args = parser.parse_args()
    if not shutil.which("xvfb-run"):
        print("SKIP: xvfb-run not found (apt-get install xvfb xauth)")
        sys.exit(SKIP)
    if args.test != "errors" and not args.encode:
        parser.error("--encode is required for " + args.test)
    {"screenshots": test_screenshots, "streaming": test_streaming, "errors": test_errors}[args.test](args)


if __name__ == "__main__":
    main()
