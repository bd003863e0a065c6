#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""pmz-view end-to-end checks under xvfb-run (Mesa's software GL).

  viewer_test.py screenshots --view BIN --encode BIN --workdir DIR
  viewer_test.py streaming   --view BIN --encode BIN --workdir DIR
  viewer_test.py errors      --view BIN --workdir DIR
  viewer_test.py attributes  --view BIN [--encode BIN] --workdir DIR

The first two encode a generated mesh with pmz-encode first; attributes renders a generated
textured OBJ (MTL + PNG checkerboard) and a vertex-coloured PLY, and with --encode streams the
textured OBJ's .pmz from a file and over HTTP (the texture fetched beside it). Exit 77 (ctest SKIP) when xvfb-run is
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


def torus_point(u, v):
    r = 0.35 * (1 + 0.18 * math.sin(5 * u) * math.cos(3 * v))
    return ((1 + r * math.cos(v)) * math.cos(u), r * math.sin(v), (1 + r * math.cos(v)) * math.sin(u))


def torus_faces(rings, segments):
    """Two triangles per grid cell, wrapping both ways: vertex (i, j) is i * segments + j."""
    faces = []
    for i in range(rings):
        for j in range(segments):
            a = i * segments + j
            b = ((i + 1) % rings) * segments + j
            c = ((i + 1) % rings) * segments + (j + 1) % segments
            d = i * segments + (j + 1) % segments
            faces += [(a, d, c), (a, c, b)]
    return faces


def write_bumpy_torus(path, rings=96, segments=48):
    """A torus with ripples: rings * segments * 2 faces, clearly visible at every size."""
    vertices = [torus_point(2 * math.pi * i / rings, 2 * math.pi * j / segments)
                for i in range(rings) for j in range(segments)]
    faces = torus_faces(rings, segments)
    with open(path, "w") as f:
        f.write("OFF\n%d %d 0\n" % (len(vertices), len(faces)))
        f.writelines("%.6f %.6f %.6f\n" % p for p in vertices)
        f.writelines("3 %d %d %d\n" % t for t in faces)
    return len(faces)


def write_png(path, width, height, rgb_rows):
    """8-bit RGB PNG from rows of bytes (filter 0)."""
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + bytes(row) for row in rgb_rows)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def write_textured_torus(directory, texture="checker.png", rings=96, segments=48):
    """The bumpy torus as an OBJ with texture coordinates (a seam where u and v wrap: those
    vertices get two wedges), an MTL naming TEXTURE, and a red / blue checkerboard PNG."""
    obj, mtl = os.path.join(directory, "textured.obj"), os.path.join(directory, "textured.mtl")
    with open(obj, "w") as f:
        f.write("mtllib textured.mtl\nusemtl checker\n")
        for i in range(rings):
            for j in range(segments):
                f.write("v %.6f %.6f %.6f\n" % torus_point(2 * math.pi * i / rings, 2 * math.pi * j / segments))
        for i in range(rings + 1):
            for j in range(segments + 1):
                f.write("vt %.6f %.6f\n" % (4.0 * i / rings, 2.0 * j / segments))
        for i in range(rings):
            for j in range(segments):
                v = [1 + (ii % rings) * segments + (jj % segments) for ii, jj in
                     ((i, j), (i, j + 1), (i + 1, j + 1), (i + 1, j))]
                t = [1 + ii * (segments + 1) + jj for ii, jj in ((i, j), (i, j + 1), (i + 1, j + 1), (i + 1, j))]
                f.write("f %d/%d %d/%d %d/%d\n" % (v[0], t[0], v[1], t[1], v[2], t[2]))
                f.write("f %d/%d %d/%d %d/%d\n" % (v[0], t[0], v[2], t[2], v[3], t[3]))
    with open(mtl, "w") as f:
        f.write("newmtl checker\nKd 1 1 1\nmap_Kd %s\n" % texture)
    size, square = 64, 8
    rows = []
    for y in range(size):
        row = bytearray()
        for x in range(size):
            row += bytes((230, 40, 30) if (x // square + y // square) % 2 else (30, 60, 230))
        rows.append(row)
    write_png(os.path.join(directory, "checker.png"), size, size, rows)
    return obj


def write_colored_torus(path, normal=None, rings=96, segments=48):
    """The bumpy torus as an ASCII PLY with a colour per vertex: red on one half, green on the
    other; with NORMAL, that one normal at every vertex (so decoded normals light it evenly)."""
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                "property float z\n%sproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                "element face %d\nproperty list uchar int vertex_indices\nend_header\n" %
                (rings * segments, "property float nx\nproperty float ny\nproperty float nz\n" if normal else "",
                 2 * rings * segments))
        for i in range(rings):
            for j in range(segments):
                p = torus_point(2 * math.pi * i / rings, 2 * math.pi * j / segments)
                color = (220, 40, 40) if i < rings // 2 else (40, 200, 60)
                f.write("%.6f %.6f %.6f " % p + ("%g %g %g " % normal if normal else "") + "%d %d %d\n" % color)
        f.writelines("3 %d %d %d\n" % t for t in torus_faces(rings, segments))


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


def saturated(p, spread=80):
    return max(p) - min(p) > spread


def colour_stats(path):
    """Among the pixels that are not background: the fraction that are strongly coloured, and
    the fractions where red or blue dominate."""
    w, h, px = pixels(path)
    background = px[0]
    shown = [p for p in px if far(p, background)]
    if len(shown) < 0.05 * len(px):
        fail("%s shows too little of the object (%.1f%%)" % (path, 100.0 * len(shown) / len(px)))
    n = float(len(shown))
    return {"covered": n / len(px), "saturated": sum(saturated(p) for p in shown) / n,
            "red": sum(p[0] > p[2] + 60 for p in shown) / n, "blue": sum(p[2] > p[0] + 60 for p in shown) / n,
            "green": sum(p[1] > p[0] + 60 for p in shown) / n}


def far(p, q, tolerance=24):
    return max(abs(a - b) for a, b in zip(p, q)) > tolerance


def require_xvfb():
    """Exits with SKIP when xvfb-run is missing."""
    if not shutil.which("xvfb-run"):
        print("SKIP: xvfb-run not found (apt-get install xvfb xauth)")
        sys.exit(SKIP)


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


def split_chunk_ends(data):
    """Where each SPLT chunk of a .pmz ends (spec/format.md section 3: u8 type, varint
    payload_size, u32 CRC, payload; SPLT is type 3, END type 4)."""
    pos, ends = 8, []
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
        if kind == 3:
            ends.append(pos)
        if kind == 4:
            break
    return ends


def check_stream(name, run, size, faces, seconds, elapsed, chunk_ends):
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
    # Each SPLT chunk that arrives is a new level to show; chunks that arrive between two log
    # lines show as one level (the base may come with the first chunk, in one slice of the
    # pipe), so at least one level per log line that saw a further chunk whole.
    levels = len(set(f for _, _, f in shown))
    chunks = len(chunk_ends)
    arrivals = len(set(sum(e <= b for e in chunk_ends) for _, b, _ in shown) - {0})
    if chunks < 3 or arrivals < 3:
        fail("%s: %d SPLT chunks arrived in %d steps; the test needs several to see levels" % (name, chunks, arrivals))
    if levels < arrivals:
        fail("%s: only %d distinct levels of detail seen while %d SPLT chunks arrived in %d steps" % (name, levels, chunks, arrivals))
    if last_t - first_t < seconds / 3:
        fail("%s: refinement did not follow the slow arrival (%.2f s from first mesh to full)" % (name, last_t - first_t))
    print("%s: PASS: %d levels from %d to %d faces over %.1f s" % (name, levels, first_faces, last_faces, last_t - first_t))


def test_streaming(args):
    pmz, faces = encode(args)
    size = os.path.getsize(pmz)
    with open(pmz, "rb") as f:
        data = f.read()
    chunk_ends = split_chunk_ends(data)

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
    check_stream("http --rate %.1f" % kbps, run, size, faces, seconds, time.monotonic() - start, chunk_ends)

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
    check_stream("stdin pipe", run, size, faces, seconds, time.monotonic() - start, chunk_ends)


def test_errors(args):
    """Each failure is one line on stderr and a non-zero exit, never a crash or a hang."""
    workdir = args.workdir
    os.makedirs(workdir, exist_ok=True)
    junk = os.path.join(workdir, "junk.pmz")
    with open(junk, "wb") as f:
        f.write(b"this is not a pmz stream at all" * 10)
    bad_obj = os.path.join(workdir, "bad.obj")
    with open(bad_obj, "w") as f:
        f.write("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    env_no_display = dict(os.environ)
    env_no_display.pop("DISPLAY", None)
    env_no_display.pop("WAYLAND_DISPLAY", None)
    cases = [
        ("missing file", [args.view, os.path.join(workdir, "missing.pmz")], None,
         "missing.pmz: cannot read: No such file or directory"),
        ("directory", [args.view, workdir], None, "directory"),
        ("no display", [args.view, junk], env_no_display, "no display"),
        ("unreachable URL", ["xvfb-run", "-a", args.view, "http://127.0.0.1:9/none.pmz"], None, "fetch failed"),
        ("not a .pmz", ["xvfb-run", "-a", args.view, junk, "--screenshot", os.path.join(workdir, "x.png")], None,
         "junk.pmz: bad magic: not a .pmz stream"),
        ("bad --size", [args.view, junk, "--size", "12"], None, "--size"),
        ("bad mesh file", [args.view, bad_obj], None, "references vertex"),
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


def screenshot(args, source, png, extra=()):
    if os.path.exists(png):
        os.remove(png)
    run = xvfb(args, [args.view, source, "--screenshot", png, "--size", "320x240"] + list(extra), 60)
    if run.returncode != 0 or not os.path.exists(png):
        fail("screenshot of %s exited %d: %s" % (source, run.returncode, run.stderr.strip()))
    print(run.stdout.strip())
    return run


def test_attributes(args):
    """Textures, vertex colours and the missing-texture warning, on mesh files shown as they are."""
    workdir = args.workdir
    os.makedirs(workdir, exist_ok=True)
    obj = write_textured_torus(workdir)
    shots = {}
    run = screenshot(args, obj, os.path.join(workdir, "textured.png"))
    if "texture coordinates" not in run.stdout or "1 material" not in run.stdout:
        fail("the textured OBJ's attributes are not reported: " + run.stdout.strip())
    if "warning" in run.stderr:
        fail("unexpected warning: " + run.stderr.strip())
    shots["textured"] = colour_stats(os.path.join(workdir, "textured.png"))
    screenshot(args, obj, os.path.join(workdir, "geometry.png"), ["--no-attributes"])
    shots["geometry"] = colour_stats(os.path.join(workdir, "geometry.png"))

    # The MTL names a texture that is not there: one warning line, drawn untextured, exit 0.
    missing = os.path.join(workdir, "missing")
    os.makedirs(missing, exist_ok=True)
    write_textured_torus(missing, texture="no-such-texture.png")
    run = screenshot(args, os.path.join(missing, "textured.obj"), os.path.join(workdir, "missing.png"))
    warnings = [line for line in run.stderr.splitlines() if line.startswith("pmz-view: warning:")]
    print("missing texture: " + (warnings[0] if warnings else "(no warning)"))
    if len(warnings) != 1 or "no-such-texture.png" not in warnings[0] or "untextured" not in warnings[0]:
        fail("want one warning line naming the missing texture, got %r" % run.stderr)
    shots["missing"] = colour_stats(os.path.join(workdir, "missing.png"))
    # ... or a file that is not an image: the same, with stb_image's reason.
    corrupt = os.path.join(workdir, "corrupt")
    os.makedirs(corrupt, exist_ok=True)
    write_textured_torus(corrupt, texture="corrupt.png")
    with open(os.path.join(corrupt, "corrupt.png"), "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n this is not a PNG after all" * 3)
    run = screenshot(args, os.path.join(corrupt, "textured.obj"), os.path.join(workdir, "corrupt.png"))
    warnings = [line for line in run.stderr.splitlines() if line.startswith("pmz-view: warning:")]
    print("corrupt texture: " + (warnings[0] if warnings else "(no warning)"))
    if len(warnings) != 1 or "not a readable image" not in warnings[0]:
        fail("want one warning line saying the texture is not a readable image, got %r" % run.stderr)

    ply = os.path.join(workdir, "colored.ply")
    write_colored_torus(ply)
    run = screenshot(args, ply, os.path.join(workdir, "colored.png"))
    if "colours" not in run.stdout:
        fail("the PLY's vertex colours are not reported: " + run.stdout.strip())
    shots["colored"] = colour_stats(os.path.join(workdir, "colored.png"))

    # Decoded normals, all the same: the colours are lit evenly, unlike the smooth normals' shading.
    even = os.path.join(workdir, "even.ply")
    write_colored_torus(even, normal=(0.3, 0.9, 0.3))
    run = screenshot(args, even, os.path.join(workdir, "even.png"))
    if "normals" not in run.stdout:
        fail("the PLY's normals are not reported: " + run.stdout.strip())
    spread = {}
    for name in ("colored", "even"):
        w, h, px = pixels(os.path.join(workdir, name + ".png"))
        red = [p[0] for p in px if p[0] > p[2] + 60]  # the red half, away from the background
        mean = sum(red) / float(len(red))
        spread[name] = math.sqrt(sum((r - mean) ** 2 for r in red) / len(red))
    print("red channel spread: smooth normals %.1f, decoded constant normals %.1f" %
          (spread["colored"], spread["even"]))
    if not spread["even"] < 0.5 * spread["colored"]:
        fail("the decoded normals do not seem to light the mesh (spread %.1f vs %.1f)" %
             (spread["even"], spread["colored"]))

    if args.encode:
        pmz = os.path.join(workdir, "textured.pmz")
        run = subprocess.run([args.encode, obj, "-o", pmz], capture_output=True, text=True, timeout=120)
        if run.returncode != 0:
            fail("pmz-encode failed (%d): %s" % (run.returncode, (run.stderr or run.stdout).strip()))
        for name, lod in (("stream-coarse", ["--ratio", "0.05"]), ("stream-full", [])):
            run = screenshot(args, pmz, os.path.join(workdir, name + ".png"), lod)
            if "texture coordinates" not in run.stdout or "warning" in run.stderr:
                fail("%s: attributes not decoded or a warning: %s %s" % (name, run.stdout, run.stderr))
            shots[name] = colour_stats(os.path.join(workdir, name + ".png"))
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(QuietHandler, directory=workdir))
        threading.Thread(target=server.serve_forever, daemon=True).start()
        url = "http://127.0.0.1:%d/textured.pmz" % server.server_address[1]
        try:
            run = screenshot(args, url, os.path.join(workdir, "stream-http.png"))
        finally:
            server.shutdown()
        if "warning" in run.stderr:
            fail("http: the texture beside the .pmz was not fetched: " + run.stderr.strip())
        shots["stream-http"] = colour_stats(os.path.join(workdir, "stream-http.png"))
        for name in ("stream-coarse", "stream-full", "stream-http"):
            if not (shots[name]["red"] > 0.15 and shots[name]["blue"] > 0.15):
                fail("%s: the checkerboard texture is not visible (red %.2f, blue %.2f)" %
                     (name, shots[name]["red"], shots[name]["blue"]))

    for name, st in shots.items():
        print("%-13s covered %.1f%%, saturated %.1f%%, red %.1f%%, blue %.1f%%, green %.1f%%" %
              (name, 100 * st["covered"], 100 * st["saturated"], 100 * st["red"], 100 * st["blue"],
               100 * st["green"]))
    t, g, m, c = shots["textured"], shots["geometry"], shots["missing"], shots["colored"]
    if not (t["red"] > 0.15 and t["blue"] > 0.15):
        fail("the checkerboard texture is not visible (red %.2f, blue %.2f)" % (t["red"], t["blue"]))
    if g["saturated"] > 0.02 or m["saturated"] > 0.02:
        fail("untextured renders should be grey (saturated: geometry %.3f, missing texture %.3f)" %
             (g["saturated"], m["saturated"]))
    if not (c["red"] > 0.15 and c["green"] > 0.15 and c["blue"] < 0.02):
        fail("the vertex colours are not visible (red %.2f, green %.2f, blue %.2f)" % (c["red"], c["green"], c["blue"]))
    print("PASS")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("test", choices=["screenshots", "streaming", "errors", "attributes"])
    parser.add_argument("--view", required=True)
    parser.add_argument("--encode")
    parser.add_argument("--workdir", required=True)
    args = parser.parse_args()
    require_xvfb()
    if args.test in ("screenshots", "streaming") and not args.encode:
        parser.error("--encode is required for " + args.test)
    {"screenshots": test_screenshots, "streaming": test_streaming, "errors": test_errors,
     "attributes": test_attributes}[args.test](args)


if __name__ == "__main__":
    main()
