#!/usr/bin/env python3
"""Regenerates the binary files of the PLY and glTF test corpora
(tests/corpus/ply/*.ply in binary encodings, tests/corpus/gltf/*) and, when
they are empty, the fuzzing seeds (tests/fuzz/corpus/{ply,pbrt}). Plain Python (struct, json,
zlib, base64), no packages. The ASCII PLY and pbrt files are text, written by
hand; the seeds copy the small ones.

Run from anywhere: python3 tests/corpus/make_formats_corpus.py
"""
import base64
import json
import os
import shutil
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
PLY = os.path.join(HERE, "ply")
GLTF = os.path.join(HERE, "gltf")
FUZZ = os.path.join(HERE, "..", "fuzz", "corpus")


def write(path, data):
    with open(path, "wb") as f:
        f.write(data)


# ------------------------------------------------------------------------ PLY

# A tetrahedron: 4 vertices with normals, s t texture coordinates and two
# properties Ferry ignores (confidence, a colour byte); 4 triangles.
TET_V = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TET_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def tet_ply(endian):
    fmt = "<" if endian == "binary_little_endian" else ">"
    header = ("ply\nformat %s 1.0\ncomment a tetrahedron\nelement vertex 4\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property float confidence\nproperty double nx\nproperty double ny\n"
              "property double nz\nproperty uchar red\nproperty float s\nproperty float t\n"
              "element face 4\nproperty list uchar int vertex_indices\n"
              "property uchar flags\nend_header\n" % endian).encode()
    body = b""
    for i, (x, y, z) in enumerate(TET_V):
        n = (x - 0.25, y - 0.25, z - 0.25)
        body += struct.pack(fmt + "ffff", x, y, z, 0.5)
        body += struct.pack(fmt + "ddd", *n)
        body += struct.pack(fmt + "B", 200)
        body += struct.pack(fmt + "ff", i * 0.25, 1 - i * 0.25)
    for f in TET_F:
        body += struct.pack(fmt + "B3iB", 3, *f, 7)
    return header, body


def quad_ply_be():
    """A unit quad as one big-endian quad face with ushort counts and uint indices."""
    header = (b"ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\n"
              b"property float y\nproperty float z\nproperty float u\nproperty float v\n"
              b"element face 1\nproperty list ushort uint vertex_indices\nend_header\n")
    body = b""
    for x, y in ((0, 0), (1, 0), (1, 1), (0, 1)):
        body += struct.pack(">fffff", x, y, 0, x, y)
    body += struct.pack(">H4I", 4, 0, 1, 2, 3)
    return header + body


def ply_corpus():
    h, b = tet_ply("binary_little_endian")
    write(os.path.join(PLY, "tet_le.ply"), h + b)
    h, b = tet_ply("binary_big_endian")
    write(os.path.join(PLY, "tet_be.ply"), h + b)
    write(os.path.join(PLY, "quad_be.ply"), quad_ply_be())
    # Truncated in the middle of the faces.
    h, b = tet_ply("binary_little_endian")
    write(os.path.join(PLY, "truncated_binary.ply"), h + b[: len(b) - 20])
    # A header promising two billion vertices over a few bytes.
    write(os.path.join(PLY, "lying_header.ply"),
          b"ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\n"
          b"property float x\nproperty float y\nproperty float z\nelement face 1\n"
          b"property list uchar int vertex_indices\nend_header\n" + b"\0" * 64)
    # A face list that claims four billion indices.
    write(os.path.join(PLY, "huge_list.ply"),
          b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
          b"property float y\nproperty float z\nelement face 1\n"
          b"property list uint int vertex_indices\nend_header\n" +
          struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<I", 4000000000) +
          struct.pack("<3i", 0, 1, 2))
    # A binary NaN position (vertex 1).
    write(os.path.join(PLY, "binary_nan.ply"),
          b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
          b"property float y\nproperty float z\nelement face 1\n"
          b"property list uchar int vertex_indices\nend_header\n" +
          struct.pack("<9f", 0, 0, 0, float("nan"), 0, 0, 0, 1, 0) + struct.pack("<B3i", 3, 0, 1, 2))
    # A binary index out of range (face 1 uses vertex 9).
    write(os.path.join(PLY, "binary_bad_index.ply"),
          b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
          b"property float y\nproperty float z\nelement face 2\n"
          b"property list uchar int vertex_indices\nend_header\n" +
          struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<B3i", 3, 0, 1, 2) +
          struct.pack("<B3i", 3, 0, 9, 2))


# ----------------------------------------------------------------------- glTF

def png(width, height, rows):
    """8-bit RGBA PNG; rows: bytes, top row first."""
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    raw = b"".join(b"\x00" + r for r in rows)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9)) +
            chunk(b"IEND", b""))


# 2x2 texture: top row red (opaque) and green (alpha 0); bottom row blue
# (opaque) and white (alpha 0). glTF v = 0 is the top row.
TEXTURE = png(2, 2, [bytes([255, 0, 0, 255, 0, 255, 0, 0]), bytes([0, 0, 255, 255, 255, 255, 255, 0])])
# 2x2 emissive texture: only the top-left texel glows.
EMISSIVE = png(2, 2, [bytes([255, 128, 0, 255, 0, 0, 0, 255]), bytes([0, 0, 0, 255, 0, 0, 0, 255])])


class Builder:
    def __init__(self):
        self.bin = bytearray()
        self.views = []
        self.accessors = []

    def view(self, data, target=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target:
            v["target"] = target
        self.bin += data
        self.views.append(v)
        return len(self.views) - 1

    def accessor(self, fmt, values, comp, type_, count, minmax=False, normalized=False):
        data = struct.pack("<" + fmt * len(values), *values)
        a = {"bufferView": self.view(data), "componentType": comp, "count": count, "type": type_}
        if normalized:
            a["normalized"] = True
        if minmax:
            n = len(values) // count
            a["min"] = [min(values[i::n]) for i in range(n)]
            a["max"] = [max(values[i::n]) for i in range(n)]
        self.accessors.append(a)
        return len(self.accessors) - 1


def quad_primitive(b, material, z=0.0):
    """Two triangles: a unit square in z = `z`, uvs from glTF's top-left origin."""
    pos = [0, 0, z, 1, 0, z, 1, 1, z, 0, 1, z]
    nor = [0, 0, 1] * 4
    uv = [0, 1, 1, 1, 1, 0, 0, 0]
    idx = [0, 1, 2, 0, 2, 3]
    return {"attributes": {"POSITION": b.accessor("f", pos, 5126, "VEC3", 4, True),
                           "NORMAL": b.accessor("f", nor, 5126, "VEC3", 4),
                           "TEXCOORD_0": b.accessor("f", uv, 5126, "VEC2", 4)},
            "indices": b.accessor("H", idx, 5123, "SCALAR", 6),
            "material": material}


def scene_document(b, images):
    s = 0.7071067811865476
    doc = {
        "asset": {"version": "2.0", "generator": "ferry make_formats_corpus.py"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength",
                           "EXT_mesh_gpu_instancing", "KHR_materials_transmission",
                           "KHR_materials_ior"],
        "scene": 0,
        "scenes": [{"nodes": [0, 5]}],
        "nodes": [
            {"name": "root", "translation": [10, 0, 0], "children": [1, 2, 3, 4]},
            {"name": "shared A", "mesh": 0, "translation": [0, 0, 1]},
            {"name": "shared B", "mesh": 0, "scale": [2, 2, 2], "rotation": [0, 0, s, s]},
            {"name": "crowd", "mesh": 1,
             "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {
                 "TRANSLATION": b.accessor("f", [0, 5, 0, 0, 6, 0, 0, 7, 0], 5126, "VEC3", 3),
                 "SCALE": b.accessor("f", [1, 1, 1, 2, 2, 2, 3, 3, 3], 5126, "VEC3", 3)}}}},
            {"name": "sun", "rotation": [-s, 0, 0, s],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "cameras", "children": [6, 7, 8]},
            {"name": "front camera node", "camera": 0, "translation": [0, 0, 20]},
            {"name": "second", "camera": 1, "translation": [0, 20, 0], "rotation": [-s, 0, 0, s]},
            {"name": "lamps", "children": [9, 10], "translation": [0, 3, 0]},
            {"name": "point", "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"name": "spot", "extensions": {"KHR_lights_punctual": {"light": 2}}},
        ],
        "meshes": [
            {"name": "card", "primitives": [quad_primitive(b, 0), quad_primitive(b, 1, 0.5)]},
            {"name": "glass", "primitives": [quad_primitive(b, 2)]},
        ],
        "materials": [
            {"name": "masked", "alphaMode": "MASK", "alphaCutoff": 0.5,
             "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0,
                                      "roughnessFactor": 0.8}},
            {"name": "glowing", "emissiveFactor": [1, 1, 1],
             "emissiveTexture": {"index": 1},
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}},
             "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.3, 0.4, 1.0], "metallicFactor": 1.0,
                                      "roughnessFactor": 0.25}},
            {"name": "glass", "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                                             "KHR_materials_ior": {"ior": 1.33}},
             "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.0}},
        ],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1}],
        "samplers": [{"wrapS": 33071, "wrapT": 33071}],
        "images": images,
        "cameras": [{"name": "front", "type": "perspective",
                     "perspective": {"yfov": 0.6, "znear": 0.1}},
                    {"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "color": [1, 0.9, 0.8], "intensity": 3},
            {"type": "point", "color": [1, 1, 1], "intensity": 50},
            {"type": "spot", "intensity": 20, "spot": {"outerConeAngle": 0.5}}]}},
    }
    return doc


def gltf_corpus():
    # .gltf + .bin + image files.
    b = Builder()
    doc = scene_document(b, [{"uri": "checker%20rgba.png"}, {"uri": "emissive.png"}])
    doc["buffers"] = [{"uri": "scene.bin", "byteLength": len(b.bin)}]
    doc["bufferViews"] = b.views
    doc["accessors"] = b.accessors
    write(os.path.join(GLTF, "scene.bin"), bytes(b.bin))
    write(os.path.join(GLTF, "scene.gltf"), json.dumps(doc, indent=1).encode())
    write(os.path.join(GLTF, "checker rgba.png"), TEXTURE)
    write(os.path.join(GLTF, "emissive.png"), EMISSIVE)

    # .glb with the images in buffer views.
    b = Builder()
    images = [{"bufferView": None, "mimeType": "image/png"}, {"bufferView": None, "mimeType": "image/png"}]
    doc = scene_document(b, images)
    images[0]["bufferView"] = b.view(TEXTURE)
    images[1]["bufferView"] = b.view(EMISSIVE)
    doc["buffers"] = [{"byteLength": len(b.bin)}]
    doc["bufferViews"] = b.views
    doc["accessors"] = b.accessors
    glb = make_glb(doc, bytes(b.bin))
    write(os.path.join(GLTF, "scene.glb"), glb)
    write(os.path.join(GLTF, "truncated.glb"), glb[: len(glb) * 2 // 3])
    write(os.path.join(GLTF, "bad_magic.glb"), b"gLTF" + glb[4:])
    lying = bytearray(glb)
    struct.pack_into("<I", lying, 8, len(glb) + 1000)
    write(os.path.join(GLTF, "lying_length.glb"), bytes(lying))

    # Everything in data: URIs.
    b = Builder()
    doc = scene_document(b, [{"uri": "data:image/png;base64," + base64.b64encode(TEXTURE).decode()},
                             {"uri": "data:image/png;base64," + base64.b64encode(EMISSIVE).decode()}])
    doc["buffers"] = [{"uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(b.bin)).decode(),
                       "byteLength": len(b.bin)}]
    doc["bufferViews"] = b.views
    doc["accessors"] = b.accessors
    write(os.path.join(GLTF, "datauri.gltf"), json.dumps(doc).encode())

    # Malformed: one triangle each, broken in one way.
    def triangle(pos=(0, 0, 0, 1, 0, 0, 0, 1, 0), idx=(0, 1, 2), count=None, extra=None):
        b = Builder()
        p = b.accessor("f", list(pos), 5126, "VEC3", 3)
        i = b.accessor("I", list(idx), 5125, "SCALAR", len(idx))
        doc = {"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "scene": 0,
               "nodes": [{"mesh": 0}],
               "meshes": [{"primitives": [{"attributes": {"POSITION": p}, "indices": i}]}]}
        if count is not None:
            b.accessors[p]["count"] = count
        if extra:
            extra(doc, b)
        data = bytes(b.bin)
        doc["buffers"] = [{"uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode(),
                           "byteLength": len(data)}]
        doc["bufferViews"] = b.views
        doc["accessors"] = b.accessors
        return json.dumps(doc).encode()

    write(os.path.join(GLTF, "accessor_overrun.gltf"), triangle(count=1000))
    write(os.path.join(GLTF, "huge_count.gltf"), triangle(count=4000000000))
    write(os.path.join(GLTF, "index_out_of_range.gltf"), triangle(idx=(0, 1, 99)))
    write(os.path.join(GLTF, "nan_position.gltf"), triangle(pos=(0, 0, 0, float("nan"), 0, 0, 0, 1, 0)))

    def missing_bin(doc, b):
        doc["buffers"] = [{"uri": "not here.bin", "byteLength": 48}]
    t = json.loads(triangle())
    t["buffers"] = [{"uri": "not here.bin", "byteLength": t["buffers"][0]["byteLength"]}]
    write(os.path.join(GLTF, "missing_bin.gltf"), json.dumps(t).encode())

    t = json.loads(triangle())
    t["nodes"] = [{"mesh": 0, "children": [1]}, {"children": [0]}]
    write(os.path.join(GLTF, "node_cycle.gltf"), json.dumps(t).encode())

    t = json.loads(triangle())
    t["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
    t["textures"] = [{"source": 0}]
    t["images"] = [{"uri": "no such image.png"}]
    t["meshes"][0]["primitives"][0]["material"] = 0
    write(os.path.join(GLTF, "missing_image.gltf"), json.dumps(t).encode())

    t = json.loads(triangle())
    t["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 7
    write(os.path.join(GLTF, "bad_accessor_index.gltf"), json.dumps(t).encode())

    write(os.path.join(GLTF, "bad_json.gltf"), b'{ "asset": { "version": "2.0" }, "nodes": [ ')

    # Material extensions with wrong values: the error names the material.
    def with_material(material, textures=0):
        t = json.loads(triangle())
        t["materials"] = [material]
        t["meshes"][0]["primitives"][0]["material"] = 0
        if textures:
            t["textures"] = [{"source": 0}] * textures
            t["images"] = [{"uri": "checker%20rgba.png"}]
        return json.dumps(t).encode()

    write(os.path.join(GLTF, "bad_ior.gltf"), with_material(
        {"name": "lens", "extensions": {"KHR_materials_ior": {"ior": -1.5}}}))
    write(os.path.join(GLTF, "bad_clearcoat.gltf"), with_material(
        {"name": "paint", "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 2}}}))
    write(os.path.join(GLTF, "bad_specular_type.gltf"), with_material(
        {"name": "shiny", "extensions": {"KHR_materials_specular": [1, 1, 1]}}))
    write(os.path.join(GLTF, "bad_transmission_texture.gltf"), with_material(
        {"name": "frosted", "extensions": {"KHR_materials_transmission": {
            "transmissionFactor": 1, "transmissionTexture": {"index": 5}}}}, textures=1))
    write(os.path.join(GLTF, "bad_texture_transform.gltf"), with_material(
        {"name": "atlas", "pbrMetallicRoughness": {"baseColorTexture": {
            "index": 0, "extensions": {"KHR_texture_transform": {"scale": "big"}}}}}, textures=1))
    write(os.path.join(GLTF, "bad_overflowing_factor.gltf"), with_material(
        {"name": "glass", "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1e39}}}))


def make_glb(doc, binary):
    j = json.dumps(doc).encode()
    while len(j) % 4:
        j += b" "
    binary = bytes(binary)
    while len(binary) % 4:
        binary += b"\0"
    total = 12 + 8 + len(j) + 8 + len(binary)
    return (struct.pack("<III", 0x46546C67, 2, total) + struct.pack("<II", len(j), 0x4E4F534A) + j +
            struct.pack("<II", len(binary), 0x004E4942) + binary)


# ------------------------------------------------------------------ fuzz seeds

def fuzz_seeds():
    """Seeds for a new fuzzing corpus. The corpus kept in the repository is
    libFuzzer's minimisation (-merge=1 -use_counters=0) of these seeds and of
    what the fuzzers found; it is only seeded when empty."""
    for kind, ext in (("ply", ".ply"), ("pbrt", ".pbrt")):
        out = os.path.join(FUZZ, kind)
        os.makedirs(out, exist_ok=True)
        if os.listdir(out):
            continue
        src = os.path.join(HERE, kind)
        for name in sorted(os.listdir(src)):
            path = os.path.join(src, name)
            if name.endswith(ext) and os.path.getsize(path) <= 4096:
                shutil.copyfile(path, os.path.join(out, "seed_" + name))


def main():
    os.makedirs(PLY, exist_ok=True)
    os.makedirs(GLTF, exist_ok=True)
    ply_corpus()
    gltf_corpus()
    fuzz_seeds()


if __name__ == "__main__":
    main()
