#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""pmz-encode's scene GLB (docs/gltf-binding.md, "Scenes") on the glTF of make_scene_gltf.py.

    test_glb_scene.py BIN_DIR WORK_DIR [VALIDATOR_DIR]

The GLB keeps the default scene's nodes (names, transforms, hierarchy), meshes (names),
materials, textures, samplers and images (the texture file embedded byte for byte) and the
extensions those use; each mesh carries its own stream in its own buffer view, every primitive of
a mesh the same extension object; the streams follow every base mesh and image, in mesh order;
each stream cut out and decoded by pmz-decode has its mesh's face count, and its HEAD agrees with
the extension and with the mesh's base primitives. glTF 2.0 structure rules are checked here
(and by the Khronos validator when scripts/install_gltf_validator.sh installed it). One mesh node
keeps the single-stream form; malformed scenes give one line, a non-zero exit and no file. One
line per failure, exit 1.
"""
import json
import os
import shutil
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(ROOT, "scripts"))
sys.path.insert(0, os.path.join(ROOT, "tests", "conformance"))
from make_scene_gltf import make  # noqa: E402
from test_glb_output import run, validate  # noqa: E402
from pmz_to_glb import read_head  # noqa: E402
from check_glb_stream import EXTENSION, check, failures, glb_parts, view_bytes  # noqa: E402

COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
SIZES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}


def check_structure(data):
    """glTF 2.0's rules on the GLB container and on references, ranges and alignment."""
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    check(magic == b"glTF" and version == 2 and length == len(data), "GLB header")
    json_len = struct.unpack_from("<I", data, 12)[0]
    check(json_len % 4 == 0 and data[20 + json_len - 1 : 20 + json_len] in (b" ", b"}"),
          "JSON chunk not padded to 4 bytes with spaces")
    gltf, blob = glb_parts(data)
    check(len(blob) % 4 == 0, "BIN chunk not padded to 4 bytes")
    buffers = gltf["buffers"]
    check(len(buffers) == 1 and "uri" not in buffers[0] and
          len(blob) - 3 <= buffers[0]["byteLength"] <= len(blob), "the GLB buffer is not the BIN chunk")
    views = gltf["bufferViews"]
    for i, v in enumerate(views):
        check(v["buffer"] == 0 and v.get("byteOffset", 0) + v["byteLength"] <= buffers[0]["byteLength"],
              f"buffer view {i} outside its buffer")
    for i, a in enumerate(gltf["accessors"]):
        v = views[a["bufferView"]]
        element = COMPONENTS[a["type"]] * SIZES[a["componentType"]]
        check((v.get("byteOffset", 0) + a.get("byteOffset", 0)) % SIZES[a["componentType"]] == 0,
              f"accessor {i} not aligned")
        check(a.get("byteOffset", 0) + element * a["count"] <= v["byteLength"], f"accessor {i} beyond its view")
        check("byteStride" not in v or v["byteStride"] % 4 == 0, f"view of accessor {i}: byteStride")
    n = len(gltf["nodes"])
    parents = {}
    for i, node in enumerate(gltf["nodes"]):
        check(not ("matrix" in node and any(k in node for k in ("translation", "rotation", "scale"))),
              f"node {i} has both matrix and TRS")
        check(node.get("mesh", 0) < len(gltf["meshes"]), f"node {i}: mesh out of range")
        for c in node.get("children", []):
            check(0 <= c < n and c not in parents and c != i, f"node {i}: child {c} (a tree of valid nodes)")
            parents[c] = i
    for r in gltf["scenes"][gltf.get("scene", 0)]["nodes"]:
        check(r not in parents, f"scene root {r} is also a child")
    for m, mesh in enumerate(gltf["meshes"]):
        for p, prim in enumerate(mesh["primitives"]):
            counts = {gltf["accessors"][a]["count"] for a in prim["attributes"].values()}
            check(len(counts) == 1, f"mesh {m} primitive {p}: attribute counts differ")
            pos = gltf["accessors"][prim["attributes"]["POSITION"]]
            check("min" in pos and "max" in pos, f"mesh {m} primitive {p}: POSITION without min/max")
            idx = gltf["accessors"][prim["indices"]]
            check(idx["componentType"] in (5121, 5123, 5125) and idx["type"] == "SCALAR" and
                  idx["count"] % 3 == 0, f"mesh {m} primitive {p}: indices")
            check(views[idx["bufferView"]].get("target", 34963) == 34963, f"mesh {m} primitive {p}: index view target")
            check(prim.get("material", 0) < len(gltf.get("materials", [])) or "material" not in prim,
                  f"mesh {m} primitive {p}: material out of range")
    for t, tex in enumerate(gltf.get("textures", [])):
        check(tex.get("source", 0) < len(gltf.get("images", [])) and tex.get("sampler", 0) < len(gltf.get("samplers", [1])),
              f"texture {t}: source or sampler out of range")
    for i, im in enumerate(gltf.get("images", [])):
        check(("uri" in im) != ("bufferView" in im) and ("bufferView" not in im or "mimeType" in im),
              f"image {i}: uri or bufferView with mimeType")
    return gltf, blob


def main():
    bin_dir, work = sys.argv[1:3]
    validator = os.path.abspath(sys.argv[3]) if len(sys.argv) > 3 else ""
    encode, decode = os.path.join(bin_dir, "pmz-encode"), os.path.join(bin_dir, "pmz-decode")
    shutil.rmtree(work, ignore_errors=True)
    src, faces = make(work)
    glb = os.path.join(work, "scene.glb")
    r = run([encode, os.path.join(work, "scene.gltf"), "-o", glb, "--quiet"])
    if not check(r.returncode == 0, f"pmz-encode scene.gltf failed: {r.stderr.strip()}"):
        return
    check(all("welded" in line for line in r.stderr.splitlines()), f"stderr: {r.stderr.strip()!r}")
    check("3 meshes (4 nodes)" in r.stdout and "GLB" in r.stdout, f"summary {r.stdout.strip()!r}")
    data = open(glb, "rb").read()
    gltf, blob = check_structure(data)

    # The default scene's nodes, in the order of a depth-first walk, with their transforms.
    kept = src["nodes"][:5]
    check([n.get("name") for n in gltf["nodes"]] == [n["name"] for n in kept], "node names or order")
    for node, want in zip(gltf["nodes"], kept):
        for k in ("translation", "rotation", "scale", "matrix", "children"):
            check(node.get(k) == want.get(k), f"node {want['name']}: {k} {node.get(k)} vs {want.get(k)}")
        check("extensions" not in node, f"node {want['name']}: extensions kept")
        mesh = node.get("mesh")
        check((mesh is None) == ("mesh" not in want) and
              (mesh is None or gltf["meshes"][mesh]["name"] == src["meshes"][want["mesh"]]["name"]),
              f"node {want['name']} names another mesh")
    check(gltf["scenes"] == [{"name": "scene", "nodes": [0]}] and gltf.get("scene", 0) == 0,
          f"scenes {gltf['scenes']}")
    # Materials, textures, samplers as the input has them; the texture file embedded.
    check(gltf["materials"] == src["materials"], f"materials {gltf['materials']}")
    check(gltf["textures"] == src["textures"] and gltf["samplers"] == src["samplers"], "textures or samplers")
    image = gltf["images"][0]
    check(image.get("name") == "checker" and image.get("mimeType") == "image/png" and
          view_bytes(gltf, blob, image["bufferView"]) == open(os.path.join(work, "checker.png"), "rb").read(),
          "the texture file is not embedded byte for byte")
    check(gltf["extensionsUsed"] == ["KHR_materials_emissive_strength", EXTENSION],
          f"extensionsUsed {gltf['extensionsUsed']}")
    check(EXTENSION not in gltf.get("extensionsRequired", []) and "extensions" not in gltf,
          "extensionsRequired or root extensions")

    # A stream per mesh, after every base and image, in mesh order.
    names = [m.get("name") for m in gltf["meshes"]]
    if not check(names == ["ring", "tube", "sheet"], f"meshes {names}"):
        return
    views = gltf["bufferViews"]
    stream_views = []
    for m, mesh in enumerate(gltf["meshes"]):
        exts = [p.get("extensions", {}).get(EXTENSION) for p in mesh["primitives"]]
        if not check(all(exts) and all(e == exts[0] for e in exts),
                     f"mesh {m}: not every primitive carries the same extension object"):
            return
        stream_views.append(exts[0]["bufferView"])
    check(len(gltf["meshes"][1]["primitives"]) == 2 and
          [p.get("material") for p in gltf["meshes"][1]["primitives"]] == [1, 2], "tube: a primitive per material")
    check("material" not in gltf["meshes"][2]["primitives"][0], "sheet has gained a material")
    check(stream_views == list(range(len(views) - 3, len(views))), f"stream views {stream_views} are not the last, in order")
    others = [v.get("byteOffset", 0) + v["byteLength"] for i, v in enumerate(views) if i not in stream_views]
    check(max(others) <= min(views[i].get("byteOffset", 0) for i in stream_views),
          "a base mesh or image lies after a stream")
    for m, (mesh, view) in enumerate(zip(gltf["meshes"], stream_views)):
        ext = mesh["primitives"][0]["extensions"][EXTENSION]
        check("target" not in views[view] and "byteStride" not in views[view], f"mesh {m}: stream view has target or stride")
        stream = view_bytes(gltf, blob, view)
        head = read_head(stream)
        check(ext["version"] == head["version"] and ext["fullFaceCount"] == head["full_faces"] and
              ext["fullVertexCount"] == head["base_vertices"] + head["total_splits"], f"mesh {m}: extension vs HEAD")
        check([list(map(float, ext["fullBounds"][k])) for k in ("min", "max")] == [head["bbox_min"], head["bbox_max"]],
              f"mesh {m}: fullBounds")
        base_faces = sum(gltf["accessors"][p["indices"]]["count"] // 3 for p in mesh["primitives"])
        check(base_faces == head["base_faces"], f"mesh {m}: {base_faces} base faces, HEAD {head['base_faces']}")
        cut, full = os.path.join(work, f"mesh{m}.pmz"), os.path.join(work, f"mesh{m}.off")
        with open(cut, "wb") as f:
            f.write(stream)
        r = run([decode, cut, "-o", full])
        if check(r.returncode == 0, f"mesh {m}: pmz-decode: {r.stderr.strip()}"):
            counts = [int(x) for x in open(full).read().split()[1:3]]
            check(counts[1] == faces[mesh["name"]] == ext["fullFaceCount"],
                  f"mesh {m}: decoded {counts[1]} faces, the input mesh has {faces[mesh['name']]}")
            check(counts[0] == ext["fullVertexCount"], f"mesh {m}: decoded {counts[0]} vertices")

    # One mesh node: the single-stream form (one node without a transform, the transform applied).
    one = dict(src, scenes=[{"nodes": [4]}], scene=0)
    with open(os.path.join(work, "one.gltf"), "w") as f:
        json.dump(one, f)
    out = os.path.join(work, "one.glb")
    r = run([encode, os.path.join(work, "one.gltf"), "-o", out, "--quiet"])
    if check(r.returncode == 0, f"pmz-encode one.gltf: {r.stderr.strip()}"):
        g, _ = glb_parts(open(out, "rb").read())
        check(g["nodes"] == [{"mesh": 0}] and len(g["meshes"]) == 1, f"one mesh node: nodes {g['nodes']}")

    # A mesh of points only: left out with a line saying so, its node kept without a mesh.
    dots = json.loads(json.dumps(src))
    dots["meshes"].append({"name": "dots", "primitives": [
        {"attributes": dict(src["meshes"][2]["primitives"][0]["attributes"]), "mode": 0}]})
    dots["nodes"].append({"name": "dots-node", "mesh": 3})
    dots["nodes"][0]["children"].append(6)
    with open(os.path.join(work, "dots.gltf"), "w") as f:
        json.dump(dots, f)
    out = os.path.join(work, "dots.glb")
    r = run([encode, os.path.join(work, "dots.gltf"), "-o", out, "--quiet"])
    if check(r.returncode == 0, f"pmz-encode dots.gltf: {r.stderr.strip()}"):
        check("mesh 3 has no triangles" in r.stderr, f"the points mesh is not named: {r.stderr.strip()!r}")
        g, _ = glb_parts(open(out, "rb").read())
        check(len(g["meshes"]) == 3 and g["nodes"][-1] == {"name": "dots-node"},
              f"points mesh: {len(g['meshes'])} meshes, last node {g['nodes'][-1]}")

    # Malformed scenes: one line naming the file, a non-zero exit, nothing written.
    bad_cases = {
        "missing-mesh": lambda g: g["nodes"][3].update(mesh=7),
        "cycle": lambda g: g["nodes"][4].update(children=[0]),
        "short-accessor": lambda g: g["accessors"][-1].update(count=10 ** 6),
        "bad-material": lambda g: g["meshes"][2]["primitives"][0].update(material=9),
    }
    for name, spoil in bad_cases.items():
        g = json.loads(json.dumps(src))
        spoil(g)
        path, out = os.path.join(work, f"{name}.gltf"), os.path.join(work, f"{name}.glb")
        with open(path, "w") as f:
            json.dump(g, f)
        r = run([encode, path, "-o", out, "--quiet"])
        lines = r.stderr.strip().splitlines()
        check(r.returncode != 0 and len(lines) == 1 and path in lines[0] and not os.path.exists(out),
              f"{name}: rc {r.returncode}, stderr {r.stderr.strip()!r}, written {os.path.exists(out)}")

    validate(validator, [glb], "test_glb_scene")

if __name__ == "__main__":
    main()
    for f in failures:
        print("FAIL:", f, file=sys.stderr)
    sys.exit(1 if failures else 0)
