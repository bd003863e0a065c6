#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""pmz-encode's GLB output (docs/gltf-binding.md) on a textured, two-material mesh.

    test_glb_output.py BIN_DIR SEAMED_OBJ WORK_DIR [VALIDATOR_DIR]

The GLB's PMZ_progressive_mesh buffer view holds the very bytes pmz-encode writes as .pmz for the
same input, as the buffer's last view; the extension's fields agree with the stream's HEAD and
with the full mesh pmz-decode makes of the embedded stream; the primitives hold the stream's base
mesh (its triangles, as position triples); materials keep their names and textures (files found
beside the input embedded, and a glTF input's own images; a missing one is kept as a URI and
named on stderr). With the Khronos
validator (scripts/install_gltf_validator.sh): 0 errors. One line per failure, exit 1.
"""
import json
import os
import shutil
import struct
import subprocess
import sys
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
sys.path.insert(0, os.path.join(ROOT, "tests", "conformance"))
from pmz_to_glb import read_head  # noqa: E402
from check_glb_stream import EXTENSION, check, failures, glb_parts, view_bytes  # noqa: E402


def png(width, height, rgb):
    """A small valid PNG of one colour."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    raw = b"".join(b"\0" + bytes(rgb) * width for _ in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def run(args):
    return subprocess.run(args, capture_output=True, text=True)


def accessor(gltf, blob, index):
    """An accessor's values as tuples (float or uint32 components, tightly packed views)."""
    a = gltf["accessors"][index]
    n = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[a["type"]]
    fmt = {5126: "f", 5125: "I"}[a["componentType"]]
    data = view_bytes(gltf, blob, a["bufferView"])[a.get("byteOffset", 0):]
    values = struct.unpack_from(f"<{a['count'] * n}{fmt}", data)
    return [tuple(values[i : i + n]) for i in range(0, len(values), n)]


def ply_mesh(path):
    """Positions (tuples) and triangles of pmz-decode's binary PLY (positions first per vertex,
    the vertex list first per face)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    counts, props, element = {}, {"vertex": [], "face": []}, None
    for line in header:
        w = line.split()
        if w[:1] == ["element"]:
            element = w[1]
            counts[element] = int(w[2])
        elif w[:1] == ["property"] and w[1] != "list":
            props[element].append(w[1])
    sizes = {"float": 4, "uchar": 1, "uint": 4, "int": 4}
    stride = sum(sizes[t] for t in props["vertex"])
    positions = [struct.unpack_from("<3f", data, end + v * stride) for v in range(counts["vertex"])]
    at, faces = end + stride * counts["vertex"], []
    face_stride = 13 + sum(sizes[t] for t in props["face"])  # uchar 3, three uint, the rest
    for _ in range(counts["face"]):
        faces.append(struct.unpack_from("<3I", data, at + 1))
        at += face_stride
    return positions, faces


def main():
    bin_dir, obj, work = sys.argv[1:4]
    validator = os.path.abspath(sys.argv[4]) if len(sys.argv) > 4 else ""
    encode, decode = os.path.join(bin_dir, "pmz-encode"), os.path.join(bin_dir, "pmz-decode")
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    for name in (obj, obj[:-4] + ".mtl"):
        shutil.copy(name, work)
    textures = {"paint.png": png(4, 4, (200, 40, 40)), "metal.png": png(2, 2, (150, 150, 170)),
                "metal_n.png": png(2, 2, (128, 128, 255))}
    for name, data in textures.items():
        with open(os.path.join(work, name), "wb") as f:
            f.write(data)
    src = os.path.join(work, os.path.basename(obj))
    pmz, glb = os.path.join(work, "seamed.pmz"), os.path.join(work, "seamed.glb")
    # A base of both materials (simplified all the way, one triangle of one material is left).
    r = run([encode, src, "-o", pmz, "--quiet", "--base-faces", "100"])
    if not check(r.returncode == 0, f"pmz-encode -o .pmz failed: {r.stderr.strip()}"):
        return
    r = run([encode, src, "-o", glb, "--quiet", "--base-faces", "100"])
    if not check(r.returncode == 0, f"pmz-encode -o .glb failed: {r.stderr.strip()}"):
        return
    check(not r.stderr, f"stderr: {r.stderr.strip()!r}")
    check("GLB" in r.stdout, f"the summary line does not mention the GLB: {r.stdout.strip()!r}")
    with open(pmz, "rb") as f:
        stream = f.read()
    with open(glb, "rb") as f:
        data = f.read()
    gltf, blob = glb_parts(data)
    head = read_head(stream)

    check(EXTENSION in gltf.get("extensionsUsed", []), "extensionsUsed lacks the extension")
    check(EXTENSION not in gltf.get("extensionsRequired", []), "the extension is required")
    prims = gltf["meshes"][0]["primitives"]
    check(len(gltf["meshes"]) == 1 and len(prims) == 2,
          f"expected one mesh of two primitives (two materials), got {len(prims)}")
    exts = [p.get("extensions", {}).get(EXTENSION) for p in prims]
    if not check(all(exts) and all(e == exts[0] for e in exts),
                 "not every primitive carries the same extension object"):
        return
    ext = exts[0]
    views = gltf["bufferViews"]
    check(ext["bufferView"] == len(views) - 1, "the stream's view is not the last one")
    sv = views[ext["bufferView"]]
    check("target" not in sv and "byteStride" not in sv, "the stream's view has target or stride")
    check(view_bytes(gltf, blob, ext["bufferView"]) == stream,
          "the embedded stream differs from the .pmz pmz-encode writes")
    check(sv.get("byteOffset", 0) + sv["byteLength"] + 3 >= len(blob),
          "the stream does not end the buffer")
    check(ext["version"] == head["version"], f"version {ext['version']} vs HEAD {head['version']}")
    check(ext["fullVertexCount"] == head["base_vertices"] + head["total_splits"], "fullVertexCount")
    check(ext["fullFaceCount"] == head["full_faces"], "fullFaceCount")
    check([list(map(float, ext["fullBounds"][k])) for k in ("min", "max")] ==
          [head["bbox_min"], head["bbox_max"]], "fullBounds differ from HEAD's bbox")

    # Materials and textures.
    names = [m.get("name") for m in gltf.get("materials", [])]
    check(names == ["paint", "metal"], f"materials {names}")
    images = gltf.get("images", [])
    embedded = {}
    for im in images:
        if "bufferView" in im:
            check(im.get("mimeType") == "image/png", f"image mimeType {im.get('mimeType')}")
            embedded[len(embedded)] = view_bytes(gltf, blob, im["bufferView"])
    check(sorted(embedded.values()) == sorted(textures.values()),
          "the texture files are not embedded byte for byte")
    check(len(embedded) == 3, f"{len(embedded)} of 3 images embedded")
    for v in views:
        check(v.get("byteOffset", 0) % 4 == 0 or "target" not in v, f"a vertex view unaligned: {v}")
    for p in prims:
        check(p.get("mode", 4) == 4 and "indices" in p, "a primitive is not indexed triangles")
        check({"POSITION", "NORMAL", "TEXCOORD_0", "COLOR_0"} <= set(p["attributes"]),
              f"attributes {sorted(p['attributes'])}")
        check(p.get("material") in (0, 1), "a primitive without its material")
    check(prims[0]["attributes"] == prims[1]["attributes"], "the primitives' vertices differ")

    # The base: the stream's level 0, as triangles of positions; the full mesh of the stream.
    cut = os.path.join(work, "cut.pmz")
    with open(cut, "wb") as f:
        f.write(view_bytes(gltf, blob, ext["bufferView"]))
    # The full mesh as OFF (position vertices: OFF has no attributes, so no vertex per wedge).
    full = os.path.join(work, "full.off")
    r = run([decode, cut, "-o", full])
    if not check(r.returncode == 0, f"pmz-decode of the embedded stream: {r.stderr.strip()}"):
        return
    counts = [int(x) for x in open(full).read().split()[1:3]]
    check(counts == [ext["fullVertexCount"], ext["fullFaceCount"]],
          f"full mesh {counts} (vertices, faces) vs the extension's")
    base = os.path.join(work, "base.ply")
    r = run([decode, cut, "-o", base, "--vertices", str(head["base_vertices"])])
    if not check(r.returncode == 0, f"pmz-decode of the embedded stream: {r.stderr.strip()}"):
        return
    base_pos, base_faces = ply_mesh(base)
    positions = accessor(gltf, blob, prims[0]["attributes"]["POSITION"])
    glb_tris = sorted(tuple(positions[i[0]] for i in t)
                      for p in prims for t in zip(*[iter(accessor(gltf, blob, p["indices"]))] * 3))
    base_tris = sorted(tuple(base_pos[v] for v in f) for f in base_faces)
    check(len(glb_tris) == head["base_faces"], f"{len(glb_tris)} base faces, HEAD {head['base_faces']}")
    check(glb_tris == base_tris, "the primitives' triangles are not the stream's base mesh")

    # A stream without attributes: one primitive, no materials.
    plain = os.path.join(work, "torus.glb")
    r = run([encode, os.path.join(os.path.dirname(obj), "torus.obj"), "--glb", "-o", plain, "--quiet"])
    if check(r.returncode == 0, f"pmz-encode --glb failed: {r.stderr.strip()}"):
        g, _ = glb_parts(open(plain, "rb").read())
        check(len(g["meshes"][0]["primitives"]) == 1 and not g.get("materials"),
              "a plain mesh's GLB is not one primitive without materials")
    # A glTF input's own images, with no file beside it: embedded again, byte for byte.
    again = os.path.join(work, "again")
    os.makedirs(again)
    shutil.copy(glb, again)
    out = os.path.join(again, "again.glb")
    r = run([encode, os.path.join(again, "seamed.glb"), "-o", out, "--quiet"])
    if check(r.returncode == 0 and "not embedded" not in r.stderr,
             f"pmz-encode of a GLB: {r.stderr.strip()}"):
        g, b = glb_parts(open(out, "rb").read())
        check(sorted(view_bytes(g, b, im["bufferView"]) for im in g.get("images", []) if "bufferView" in im)
              == sorted(textures.values()), "a GLB input's images are not embedded again")
    # A texture file that is missing: named on stderr, kept as a URI.
    os.remove(os.path.join(work, "metal_n.png"))
    missing = os.path.join(work, "missing-texture.glb")
    r = run([encode, src, "-o", missing, "--quiet"])
    if check(r.returncode == 0, f"pmz-encode with a texture missing failed: {r.stderr.strip()}"):
        check("metal_n.png" in r.stderr and "not embedded" in r.stderr,
              f"the missing texture is not named on stderr: {r.stderr.strip()!r}")
        g, _ = glb_parts(open(missing, "rb").read())
        check([im.get("uri") for im in g["images"] if "uri" in im] == ["metal_n.png"],
              "the missing texture is not kept as a URI")
    # Bad input: one line, non-zero exit, nothing written.
    bad = os.path.join(work, "missing.glb")
    r = run([encode, os.path.join(work, "no-such.obj"), "-o", bad, "--quiet"])
    check(r.returncode != 0 and not os.path.exists(bad) and len(r.stderr.strip().splitlines()) == 1,
          f"a missing input: rc {r.returncode}, stderr {r.stderr.strip()!r}")

    validate(validator, [glb, plain], "test_glb_output")


def validate(validator, files, test):
    """The Khronos validator's verdict on each file (0 errors), when it is installed."""
    if validator and os.path.exists(os.path.join(validator, "node_modules", "gltf-validator")):
        for f in files:
            r = run(["node", os.path.join(ROOT, "tests", "meshio", "validate_gltf.js"), validator, f])
            check(r.returncode == 0 and "errors 0" in r.stdout,
                  f"validator on {f}:\n{r.stdout}{r.stderr}")
    else:
        print(f"{test}: gltf-validator not installed, not validated")


if __name__ == "__main__":
    main()
    for f in failures:
        print("FAIL:", f, file=sys.stderr)
    sys.exit(1 if failures else 0)
