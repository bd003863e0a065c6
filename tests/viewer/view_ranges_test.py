#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""pmz-view decoding for a camera, end to end under xvfb-run.

  view_ranges_test.py ranges --view BIN --encode BIN --generate BIN --workdir DIR
  view_ranges_test.py cracks --view BIN --encode BIN --workdir DIR

ranges: a generated terrain encoded in nodes, served by nginx (127.0.0.1, a free port, a
temporary prefix; no root needed), shown with --camera close to the ground: the screenshot shows
the ground, fewer bytes than the file went over the wire (nginx's access log) and they were
asked with Range; from the file with --max-faces, at most that many faces. Then the same from a server that ignores Range (200 with the whole body: the
viewer reads it in order and shows the same faces), and from servers that answer a node's range
with other bytes or too few: one line naming the URL and the reason, exit 1, no PNG, no hang.
cracks: a closed mesh (the bumpy torus) encoded in small nodes, seen so that nodes of several
levels are resident at once: no background pixel shows through the surface.

Exit 77 (ctest SKIP) when xvfb-run or nginx is missing. Standard library only.
"""
import argparse
import functools
import http.server
import os
import re
import shutil
import socket
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import viewer_test as vt  # noqa: E402  (PNG decoding, the torus, xvfb-run)

BACKGROUND = (33, 36, 41)  # viewer/renderer.hpp kBackground, as 8-bit
CLOSE_CAMERA = "0.2,0.15,0.12,0.2,0.25,0"  # over the terrain's (0, 0)-(1, 1) corner
SIZE = "320x240"
KBPS = 40


def is_background(p, tolerance=6):
    return max(abs(a - b) for a, b in zip(p, BACKGROUND)) <= tolerance


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for_port(port, process, seconds=10):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if process.poll() is not None:
            return False
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.5):
                return True
        except OSError:
            time.sleep(0.05)
    return False


class Nginx:
    """nginx in the foreground with everything under `prefix`; its access log has the status,
    the body bytes sent and the Range header of each request."""

    def __init__(self, prefix, root):
        self.prefix, self.port = prefix, free_port()
        for d in ("logs", "temp"):
            os.makedirs(os.path.join(prefix, d), exist_ok=True)
        self.access_log = os.path.join(prefix, "logs", "access.log")
        temp = os.path.join(prefix, "temp")
        conf = os.path.join(prefix, "nginx.conf")
        with open(conf, "w") as f:
            # As root its workers would switch to nobody, who may not read the build tree.
            f.write("user root;\n" if os.geteuid() == 0 else "")
            f.write("daemon off;\nworker_processes 1;\npid %s/nginx.pid;\nerror_log %s/logs/error.log;\n"
                    "events { worker_connections 64; }\n"
                    "http {\n  log_format ranges '$status $body_bytes_sent \"$http_range\"';\n"
                    "  access_log %s ranges;\n"
                    "  client_body_temp_path %s/body;\n  proxy_temp_path %s/proxy;\n"
                    "  fastcgi_temp_path %s/fastcgi;\n  uwsgi_temp_path %s/uwsgi;\n  scgi_temp_path %s/scgi;\n"
                    "  server { listen 127.0.0.1:%d; root %s; }\n}\n" %
                    (prefix, prefix, self.access_log, temp, temp, temp, temp, temp, self.port, root))
        self.process = subprocess.Popen(["nginx", "-p", prefix, "-e", os.path.join(prefix, "logs", "error.log"),
                                         "-c", conf], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        if not wait_for_port(self.port, self.process):
            self.stop()
            vt.fail("nginx did not start: " + self.process.stderr.read().decode(errors="replace"))

    def requests(self):
        """(status, bytes sent, Range header) per request so far."""
        with open(self.access_log) as f:
            return [(int(m.group(1)), int(m.group(2)), m.group(3))
                    for m in (re.match(r'(\d+) (\d+) "(.*)"', line) for line in f) if m]

    def stop(self):
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


def shoot(args, source, png, camera, pixel_error="1"):
    if os.path.exists(png):
        os.remove(png)
    return vt.xvfb(args, [args.view, source, "--camera", camera, "--pixel-error", pixel_error, "--size", SIZE,
                          "--screenshot", png, "--exit-when-complete"], 60)


def shot_summary(name, run, png):
    """Faces, bytes read and nodes from the 'wrote' line; fails unless it exited 0 with a PNG."""
    if run.returncode != 0 or not os.path.exists(png):
        vt.fail("%s: exited %d: %s" % (name, run.returncode, run.stderr.strip()[-600:]))
    print("%s: %s" % (name, run.stdout.strip()))
    m = re.search(r"(\d+) faces, \d+ vertices, (\d+) of (\d+) bytes read, (\d+) of (\d+) nodes", run.stdout)
    if not m:
        vt.fail("%s: no summary line: %r" % (name, run.stdout))
    if int(m.group(2)) > int(m.group(3)):
        vt.fail("%s: more bytes read than the stream has" % name)
    return tuple(int(g) for g in m.groups())


def covered(png):
    width, height, px = vt.pixels(png)
    return sum(not is_background(p) for p in px) / len(px)


class RangeIgnoring(http.server.SimpleHTTPRequestHandler):
    """Answers every GET with 200 and the whole file (http.server ignores Range), noting the
    Range headers it was asked with."""
    ranges = []

    def do_GET(self):
        RangeIgnoring.ranges.append(self.headers.get("Range"))
        super().do_GET()

    def log_message(self, *args):
        pass


class BadRanges(http.server.BaseHTTPRequestHandler):
    """Honours Range for the pieces read in order up to the node table (4 KiB, then doubling)
    but answers a node's range with the bytes one further on ('shifted') or with half of them
    ('short')."""
    data, mode, spoilt = b"", "shifted", 0
    in_order = {0} | {4096 * (2 ** k - 1) for k in range(1, 20)}

    def do_GET(self):
        m = re.match(r"bytes=(\d+)-(\d+)", self.headers.get("Range", ""))
        first, last = (int(m.group(1)), min(int(m.group(2)), len(self.data) - 1)) if m else (0, len(self.data) - 1)
        body = self.data[first:last + 1]
        if first not in self.in_order:
            body = (self.data + b"\0")[first + 1:last + 2] if self.mode == "shifted" else body[:len(body) // 2]
            BadRanges.spoilt += 1
        self.send_response(206)
        self.send_header("Content-Range", "bytes %d-%d/%d" % (first, last, len(self.data)))
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *args):
        pass


def serve(handler):
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def make_terrain(args, workdir):
    ply, pmz = os.path.join(workdir, "terrain.ply"), os.path.join(workdir, "terrain.pmz")
    for command in ([args.generate, "--faces", "100000", "-q", "-o", ply],
                    [args.encode, ply, "--cluster-vertices", "1000", "-o", pmz]):
        run = subprocess.run(command, capture_output=True, text=True, timeout=120)
        if run.returncode != 0:
            vt.fail("%s failed: %s" % (os.path.basename(command[0]), run.stderr.strip()))
    return pmz


def test_ranges(args):
    if not shutil.which("nginx"):
        print("SKIP: nginx not found (apt-get install nginx)")
        sys.exit(vt.SKIP)
    workdir = args.workdir
    os.makedirs(workdir, exist_ok=True)
    www, prefix = os.path.join(workdir, "www"), os.path.join(workdir, "nginx")
    for d in (www, prefix):
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
    pmz = make_terrain(args, www)
    size = os.path.getsize(pmz)
    name = os.path.basename(pmz)

    # From the file by seek + read: the reference for the runs over HTTP.
    png = os.path.join(workdir, "file.png")
    faces, read, total, nodes, all_nodes = shot_summary("file", shoot(args, pmz, png, CLOSE_CAMERA), png)
    if not (total == size and read < size and 1 < nodes < all_nodes):
        vt.fail("file: a close view should read part of the %d bytes and some of the nodes" % size)
    # --max-faces: within half the faces, from fewer nodes and bytes; the summary names it.
    budget = faces // 2
    png = os.path.join(workdir, "budget.png")
    run = vt.xvfb(args, [args.view, pmz, "--camera", CLOSE_CAMERA, "--size", SIZE, "--max-faces", str(budget),
                         "--screenshot", png, "--exit-when-complete"], 60)
    got = shot_summary("--max-faces %d" % budget, run, png)
    if not (got[0] <= budget and got[1] < read and 1 < got[3] < nodes and
            "budget %d faces" % budget in run.stdout):
        vt.fail("--max-faces %d: want at most that many faces from fewer bytes and nodes than %s: %s" %
                (budget, (faces, read, nodes), run.stdout.strip()))

    # Without --camera the window's orbit camera (framing the whole terrain) is the view.
    orbit = vt.xvfb(args, [args.view, pmz, "--size", SIZE, "--pixel-error", "0.5", "--log", "--exit-when-complete"],
                    60)
    lines = [line for line in orbit.stderr.splitlines() if line.startswith("t=")]
    print("orbit camera: " + (lines[-1] if lines else orbit.stderr.strip()[-300:]))
    last = dict(re.findall(r"(\w+)=([\d.]+)", lines[-1])) if lines else {}
    if orbit.returncode != 0 or not lines[-1].endswith("complete") or not 1 < int(last["nodes"]) < all_nodes or \
            not int(last["bytes"]) < size:
        vt.fail("orbit camera: want a complete view from some of the nodes and bytes")

    nginx = Nginx(prefix, www)
    try:
        url = "http://127.0.0.1:%d/%s" % (nginx.port, name)
        png = os.path.join(workdir, "nginx.png")
        got = shot_summary("nginx", shoot(args, url, png, CLOSE_CAMERA), png)
        requests = nginx.requests()
        # The same view decoded interactively, with --log lines to parse, at --rate KBPS: the
        # nodes' bytes wait their turn too.
        log_run = vt.xvfb(args, [args.view, url, "--camera", CLOSE_CAMERA, "--size", SIZE, "--log", "--rate",
                                 str(KBPS), "--exit-when-complete"], 60)
    finally:
        nginx.stop()
    sent = sum(r[1] for r in requests)
    partial = sum(r[0] == 206 and r[2].startswith("bytes=") for r in requests)
    print("nginx: %d requests, %d answered 206 to a Range, %d of %d bytes sent" % (len(requests), partial, sent, size))
    if got != (faces, read, total, nodes, all_nodes):
        vt.fail("nginx: the view over HTTP differs from the file's: %s vs %s" % (got, (faces, read, total, nodes,
                                                                                      all_nodes)))
    if partial < 2 or partial != len(requests):
        vt.fail("nginx: every request should be a Range answered 206: %s" % requests)
    if sent >= size or sent != read:
        vt.fail("nginx: %d bytes sent for the view, the viewer counted %d; the file has %d" % (sent, read, size))
    if covered(png) < 0.9:
        vt.fail("nginx: the close view should be filled by the ground (%.1f%% covered)" % (100 * covered(png)))
    lines = [line for line in log_run.stderr.splitlines() if line.startswith("t=")]
    last = dict(re.findall(r"(\w+)=([\d.]+)", lines[-1])) if lines else {}
    print("log: " + (lines[-1] if lines else log_run.stderr.strip()[-300:]))
    if log_run.returncode != 0 or not lines[-1].endswith("complete") or int(last["faces"]) != faces or \
            not int(last["bytes"]) < int(last["total"]) == size or int(last["nodes"]) != nodes:
        vt.fail("--log: the interactive run should end complete at the screenshot's faces and nodes")
    if float(last["t"]) < 0.95 * read / (KBPS * 1000):  # (the in-order bytes alone take 2/3 of it)
        vt.fail("--rate %d: %d bytes in %.2f s" % (KBPS, read, float(last["t"])))

    # A server that ignores Range: asked with Range, answered 200; read in order, same view.
    RangeIgnoring.ranges = []
    server = serve(functools.partial(RangeIgnoring, directory=www))
    try:
        url = "http://127.0.0.1:%d/%s" % (server.server_address[1], name)
        png = os.path.join(workdir, "ignoring.png")
        whole = shot_summary("ignores Range", shoot(args, url, png, CLOSE_CAMERA), png)
    finally:
        server.shutdown()
    if not RangeIgnoring.ranges or not RangeIgnoring.ranges[0] or len(RangeIgnoring.ranges) != 1:
        vt.fail("ignores Range: want one request, made with Range: %s" % RangeIgnoring.ranges)
    # (The view may be complete before the body's end: the viewer then stops reading.)
    if whole[0] != faces or not read <= whole[1] <= size or covered(png) < 0.9:
        vt.fail("ignores Range: want the same %d faces from at most %d bytes, got %s" % (faces, size, whole))

    # Node ranges answered with other bytes, or too few: one line, exit 1, no PNG.
    with open(pmz, "rb") as f:
        BadRanges.data = f.read()
    for mode, reason in (("shifted", "checksum"), ("short", "bytes answered")):
        BadRanges.mode, BadRanges.spoilt = mode, 0
        server = serve(BadRanges)
        try:
            url = "http://127.0.0.1:%d/%s" % (server.server_address[1], name)
            png = os.path.join(workdir, "bad.png")
            start = time.monotonic()
            run = shoot(args, url, png, CLOSE_CAMERA)
        finally:
            server.shutdown()
        lines = [line for line in run.stderr.splitlines() if line.startswith("pmz-view:")]
        print("%s: rc=%d in %.1f s: %s" % (mode, run.returncode, time.monotonic() - start, lines))
        if not BadRanges.spoilt or run.returncode != 1 or len(lines) != 1 or url not in lines[0] or \
                reason not in lines[0] or os.path.exists(png):
            vt.fail("%s ranges: want one line naming %s and '%s', exit 1, no PNG; got rc=%d %r" %
                    (mode, url, reason, run.returncode, run.stderr))
    print("PASS")


def holes(px, width, height):
    """Background pixels (exactly the clear colour) that do not reach the border through
    background: seen through the surface, where no view of the mesh shows background."""
    bg = [p == BACKGROUND for p in px]
    seen = [False] * len(px)
    stack = [i for i in range(len(px)) if bg[i] and (i < width or i >= len(px) - width or i % width in (0, width - 1))]
    for i in stack:
        seen[i] = True
    while stack:
        i = stack.pop()
        x, y = i % width, i // width
        for nx, ny in ((x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)):
            j = ny * width + nx
            if 0 <= nx < width and 0 <= ny < height and bg[j] and not seen[j]:
                seen[j] = True
                stack.append(j)
    return sum(bg[i] and not seen[i] for i in range(len(px)))


def test_cracks(args):
    workdir = args.workdir
    os.makedirs(workdir, exist_ok=True)
    off, pmz = os.path.join(workdir, "torus.off"), os.path.join(workdir, "torus.pmz")
    vt.write_bumpy_torus(off, rings=192, segments=96)
    run = subprocess.run([args.encode, off, "--cluster-vertices", "300", "-o", pmz], capture_output=True, text=True,
                         timeout=120)
    if run.returncode != 0:
        vt.fail("pmz-encode failed: " + run.stderr.strip())
    # The whole ring from low down (its hole hidden: all background reaches the border), and
    # from just outside the tube (the surface fills the view: no background at all), each with
    # nodes of several levels resident.
    for name, camera in (("ring", "0,0.25,-3,0,0,0"), ("tube", "0,0.2,-1.7,0,0,-1")):
        png = os.path.join(workdir, name + ".png")
        faces, read, total, nodes, all_nodes = shot_summary(name, shoot(args, pmz, png, camera, "0.25"), png)
        if not 1 < nodes < all_nodes:
            vt.fail("%s: the view should need some of the %d nodes, not %d" % (name, all_nodes, nodes))
        width, height, px = vt.pixels(png)
        found = holes(px, width, height)
        print("%s: %d of %d nodes resident, %.1f%% covered, %d background pixels inside the surface" %
              (name, nodes, all_nodes, 100 * covered(png), found))
        # The counter finds a one-pixel hole punched into the surface.
        inside = next(i for i in range(len(px) // 2 + width // 2, len(px) - width) if 0 < i % width < width - 1 and
                      all(not is_background(px[j]) for j in (i, i - 1, i + 1, i - width, i + width)))
        if holes(px[:inside] + [BACKGROUND] + px[inside + 1:], width, height) != found + 1:
            vt.fail("the hole counter misses a punched pixel")
        if found:
            vt.fail("%s: %d background pixels show through the surface" % (name, found))
    print("PASS")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("test", choices=["ranges", "cracks"])
    parser.add_argument("--view", required=True)
    parser.add_argument("--encode", required=True)
    parser.add_argument("--generate")
    parser.add_argument("--workdir", required=True)
    args = parser.parse_args()
    vt.require_xvfb()
    if args.test == "ranges" and not args.generate:
        parser.error("--generate is required for ranges")
    {"ranges": test_ranges, "cracks": test_cracks}[args.test](args)


if __name__ == "__main__":
    main()
