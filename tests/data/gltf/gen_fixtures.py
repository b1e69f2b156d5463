#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Writes the glTF fixtures of tests/unit/test_gltf.c into this folder.

The outputs are committed; run this only to change them:
    python3 tests/data/gltf/gen_fixtures.py
Deterministic: the same script writes the same bytes.
"""
import base64
import json
import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))

FLOAT, UBYTE, USHORT, UINT = 5126, 5121, 5123, 5125


def data_uri(b):
    return "data:application/octet-stream;base64," + base64.b64encode(b).decode()


def f32(*v):
    return struct.pack("<%df" % len(v), *v)


def png(width, height, pixels, channels=4, bits=8):
    """pixels: rows of tuples of `channels` values."""
    color_type = {1: 0, 2: 4, 3: 2, 4: 6}[channels]
    raw = b""
    for row in pixels:
        raw += b"\x00"
        for px in row:
            for c in px:
                raw += struct.pack(">H", c) if bits == 16 else bytes([c])

    def chunk(kind, body):
        return (struct.pack(">I", len(body)) + kind + body +
                struct.pack(">I", zlib.crc32(kind + body) & 0xffffffff))

    ihdr = struct.pack(">IIBBBBB", width, height, bits, color_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


class Doc:
    """A glTF document with one growing binary buffer."""

    def __init__(self):
        self.bin = b""
        self.g = {"asset": {"version": "2.0", "generator": "gen_fixtures.py"},
                  "buffers": [], "bufferViews": [], "accessors": []}

    def view(self, data, stride=None):
        while len(self.bin) % 4:
            self.bin += b"\x00"
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if stride:
            v["byteStride"] = stride
        self.bin += data
        self.g["bufferViews"].append(v)
        return len(self.g["bufferViews"]) - 1

    def accessor(self, data, ctype, type_, count, normalized=False, **extra):
        a = {"bufferView": self.view(data), "componentType": ctype, "count": count, "type": type_}
        if normalized:
            a["normalized"] = True
        a.update(extra)
        self.g["accessors"].append(a)
        return len(self.g["accessors"]) - 1

    def positions(self, pts):
        flat = [c for p in pts for c in p]
        lo = [min(p[i] for p in pts) for i in range(3)]
        hi = [max(p[i] for p in pts) for i in range(3)]
        return self.accessor(f32(*flat), FLOAT, "VEC3", len(pts), min=lo, max=hi)

    def indices(self, idx, ctype=USHORT):
        fmt = {UBYTE: "B", USHORT: "H", UINT: "I"}[ctype]
        return self.accessor(struct.pack("<%d%s" % (len(idx), fmt), *idx), ctype, "SCALAR", len(idx))

    def finish(self, uri=None):
        b = {"byteLength": len(self.bin)}
        if uri is not None:
            b["uri"] = uri
        self.g["buffers"] = [b]
        return self.g

    def embedded(self):
        return self.finish(data_uri(self.bin))


def write(name, obj):
    with open(os.path.join(HERE, name), "w") as f:
        json.dump(obj, f, indent=1, sort_keys=True)
        f.write("\n")


def write_bytes(name, data):
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data)


def glb(gltf, bin_data):
    js = json.dumps(gltf, sort_keys=True, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    bin_data += b"\x00" * (-len(bin_data) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(bin_data), 0x004E4942) + bin_data
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


TRI = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
QUAD = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)]


def one_triangle():
    d = Doc()
    pos = d.positions(TRI)
    d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": pos}}]}]
    d.g["nodes"] = [{"mesh": 0}]
    d.g["scenes"] = [{"nodes": [0]}]
    d.g["scene"] = 0
    return d


def modes():
    """Strip, fan, then the skipped points/lines/line loop/line strip."""
    d = Doc()
    strip = d.positions(QUAD)  # 0,1,2,3: two CCW triangles as a strip
    fan = d.positions([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)])
    prims = [{"attributes": {"POSITION": strip}, "mode": 5},
             {"attributes": {"POSITION": fan}, "mode": 6}]
    for mode in (0, 1, 2, 3):
        prims.append({"attributes": {"POSITION": strip}, "mode": mode})
    d.g["meshes"] = [{"name": "modes", "primitives": prims}]
    d.g["nodes"] = [{"mesh": 0}]
    d.g["scenes"] = [{"nodes": [0]}]
    write("modes.gltf", d.embedded())


def indices():
    """The same quad as u8, u16 and u32 indices and without indices."""
    d = Doc()
    pos = d.positions(QUAD)
    tri = [0, 1, 2, 1, 3, 2]
    flat = d.positions([QUAD[i] for i in tri])
    prims = [{"attributes": {"POSITION": pos}, "indices": d.indices(tri, c)} for c in (UBYTE, USHORT, UINT)]
    prims.append({"attributes": {"POSITION": flat}})
    d.g["meshes"] = [{"primitives": prims}]
    d.g["nodes"] = [{"mesh": 0}]
    d.g["scenes"] = [{"nodes": [0]}]
    write("indices.gltf", d.embedded())


def hierarchy():
    """Root: TRS (t = (10,0,0), 90 deg about z, scale 2); child: a matrix
    translating by (0,1,0) holding a triangle; a second root, a plain
    instance of the same mesh; node 3 is in no scene."""
    d = Doc()
    pos = d.positions(TRI)
    s = math.sqrt(0.5)
    d.g["meshes"] = [{"name": "tri", "primitives": [{"attributes": {"POSITION": pos}}]}]
    d.g["nodes"] = [
        {"name": "root", "translation": [10, 0, 0], "rotation": [0, 0, s, s], "scale": [2, 2, 2],
         "children": [1]},
        {"name": "child", "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 1, 0, 1], "mesh": 0},
        {"name": "plain", "mesh": 0},
        {"name": "elsewhere", "mesh": 0},
    ]
    d.g["scenes"] = [{"nodes": [3]}, {"nodes": [0, 2]}]
    d.g["scene"] = 1
    write("hierarchy.gltf", d.embedded())


def no_scene():
    d = Doc()
    pos = d.positions(TRI)
    d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": pos}}]}]
    d.g["nodes"] = [{"children": [2]}, {"mesh": 0}, {"mesh": 0}, {}]
    write("no_scene.gltf", d.embedded())


PIXELS = [[(128, 64, 255, 255), (0, 255, 32, 128)],
          [(255, 255, 255, 0), (10, 20, 30, 40)]]


def materials():
    """Material 0 uses one 2x2 RGBA texture as base colour (sRGB), metallic-
    roughness (linear) and emission (sRGB): two lie_textures.  Material 1 has
    the defaults plus a 1x1 16-bit grey texture.  UVs are normalized u8."""
    d = Doc()
    pos = d.positions(TRI)
    nrm = d.accessor(f32(0, 0, 1, 0, 0, 1, 0, 0, 1), FLOAT, "VEC3", 3)
    uv = d.accessor(bytes([0, 0, 255, 0, 0, 255, 0, 0]), UBYTE, "VEC2", 3, normalized=True)
    d.g["meshes"] = [{"primitives": [
        {"attributes": {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv}, "material": 0},
        {"attributes": {"POSITION": pos}, "material": 1},
        {"attributes": {"POSITION": pos}}]}]
    d.g["nodes"] = [{"mesh": 0}]
    d.g["scenes"] = [{"nodes": [0]}]
    img16 = d.view(png(1, 1, [[(40000,)]], channels=1, bits=16))
    d.g["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(png(2, 2, PIXELS)).decode()},
                     {"bufferView": img16, "mimeType": "image/png"}]
    d.g["samplers"] = [{"wrapS": 33071, "wrapT": 33648}]
    d.g["textures"] = [{"source": 0, "sampler": 0}, {"source": 1}]
    d.g["materials"] = [
        {"name": "textured",
         "pbrMetallicRoughness": {"baseColorFactor": [0.5, 1, 1, 1], "baseColorTexture": {"index": 0},
                                  "metallicFactor": 0.25, "roughnessFactor": 0.75,
                                  "metallicRoughnessTexture": {"index": 0}},
         "emissiveFactor": [1, 0.5, 0], "emissiveTexture": {"index": 0},
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}},
         "doubleSided": True},
        {"pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}},
    ]
    d.g["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    write("materials.gltf", d.embedded())


def lights_cameras():
    d = one_triangle()
    d.g["extensionsUsed"] = ["KHR_lights_punctual"]
    d.g["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"type": "point", "name": "bulb", "color": [1, 0.5, 0.25], "intensity": 10, "range": 5},
        {"type": "spot", "spot": {}},
        {"type": "directional", "intensity": 3}]}}
    d.g["cameras"] = [
        {"type": "perspective", "name": "persp", "perspective": {"yfov": 0.5, "aspectRatio": 1.5, "znear": 0.1}},
        {"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.01}},
        {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}]
    d.g["nodes"] += [
        {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 2, 0]},
        {"extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"extensions": {"KHR_lights_punctual": {"light": 2}}},
        {"camera": 0, "translation": [0, 0, 5]}, {"camera": 1}, {"camera": 2}]
    d.g["scenes"] = [{"nodes": [0, 1, 2, 3, 4, 5, 6]}]
    write("lights_cameras.gltf", d.embedded())


def sparse():
    """POSITION: the triangle with vertex 2 replaced through a sparse
    accessor; NORMAL: no bufferView (zeros) with vertex 1 set sparsely."""
    d = Doc()
    base = d.view(f32(*[c for p in TRI for c in p]))
    sidx = d.view(struct.pack("<H", 2) + b"\x00\x00")
    sval = d.view(f32(0, 3, 0))
    nidx = d.view(bytes([1, 0, 0, 0]))
    nval = d.view(f32(0, 0, 1))
    d.g["accessors"] = [
        {"bufferView": base, "componentType": FLOAT, "count": 3, "type": "VEC3",
         "sparse": {"count": 1, "indices": {"bufferView": sidx, "componentType": USHORT},
                    "values": {"bufferView": sval}}},
        {"componentType": FLOAT, "count": 3, "type": "VEC3",
         "sparse": {"count": 1, "indices": {"bufferView": nidx, "componentType": UBYTE},
                    "values": {"bufferView": nval}}}]
    d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}}]}]
    d.g["nodes"] = [{"mesh": 0}]
    d.g["scenes"] = [{"nodes": [0]}]
    write("sparse.gltf", d.embedded())


def binary():
    """A .glb: triangle and an image in the BIN chunk; the same bytes under a
    .gltf name, and a JSON glTF under a .glb name."""
    d = one_triangle()
    img = d.view(png(2, 2, PIXELS))
    d.g["images"] = [{"bufferView": img, "mimeType": "image/png"}]
    d.g["textures"] = [{"source": 0}]
    d.g["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
    d.g["meshes"][0]["primitives"][0]["material"] = 0
    g = d.finish()
    data = glb(g, d.bin)
    write_bytes("triangle.glb", data)
    write_bytes("glb_named.gltf", data)
    write_bytes("truncated.glb", data[:len(data) - 40])
    # BIN chunk header claims 8 bytes more than the file (tinygltf's own check misses this)
    js_len = struct.unpack("<I", data[12:16])[0]
    at = 20 + js_len
    bad = bytearray(data)
    struct.pack_into("<I", bad, at, struct.unpack("<I", data[at:at + 4])[0] + 4)
    write_bytes("bin_overrun.glb", bytes(bad))
    # an image bufferView beyond the BIN chunk (tinygltf decodes it unchecked)
    g2 = json.loads(json.dumps(g))
    g2["bufferViews"][img]["byteOffset"] = 4096
    write_bytes("image_view_oob.glb", glb(g2, d.bin))
    write("json_named.glb", one_triangle().embedded())


def external():
    """External .bin and .png next to the .gltf, with a space in a name."""
    d = one_triangle()
    uv = d.accessor(f32(0, 0, 1, 0, 0, 1), FLOAT, "VEC2", 3)
    d.g["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = uv
    d.g["images"] = [{"uri": "ext%20image.png"}]
    d.g["textures"] = [{"source": 0}]
    d.g["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
    d.g["meshes"][0]["primitives"][0]["material"] = 0
    write("external.gltf", d.finish("external.bin"))
    write_bytes("external.bin", d.bin)
    write_bytes("ext image.png", png(2, 2, PIXELS))
    g = json.loads(json.dumps(d.g))
    g["images"] = [{"uri": "no_such_image.png"}]
    write("missing_image.gltf", g)
    g = json.loads(json.dumps(d.g))
    g["buffers"][0]["uri"] = "no_such.bin"
    write("missing_bin.gltf", g)
    # a folder whose file reaches back out for its buffer
    os.makedirs(os.path.join(HERE, "escape"), exist_ok=True)
    g = json.loads(json.dumps(d.g))
    g["buffers"][0]["uri"] = "../external.bin"
    g["images"][0]["uri"] = "../ext%20image.png"
    write("escape/escape.gltf", g)
    g = json.loads(json.dumps(d.g))
    g["buffers"][0]["uri"] = "sub/../external.bin"
    os.makedirs(os.path.join(HERE, "sub"), exist_ok=True)
    write_bytes("sub/.keep", b"")
    write("inside_dotdot.gltf", g)


def limits():
    """A 2-triangle mesh instanced by three nodes: 2 in the document, 6 in the world."""
    d = Doc()
    pos = d.positions(QUAD)
    d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": pos}, "indices": d.indices([0, 1, 2, 1, 3, 2])}]}]
    d.g["nodes"] = [{"mesh": 0}, {"mesh": 0, "translation": [2, 0, 0]}, {"mesh": 0, "translation": [4, 0, 0]}]
    d.g["scenes"] = [{"nodes": [0, 1, 2]}]
    write("instanced.gltf", d.embedded())


def bad():
    write_bytes("bad_json.gltf", b'{\n  "asset": {"version": "2.0"},\n  "nodes": [ {"mesh": 0,, } ]\n}\n')
    write_bytes("empty.gltf", b"")

    d = one_triangle()
    d.g["accessors"][0]["count"] = 4  # 48 bytes from a 36-byte view
    write("accessor_oob.gltf", d.embedded())

    d = one_triangle()
    d.g["accessors"][0]["byteOffset"] = 4
    write("accessor_offset_oob.gltf", d.embedded())

    d = one_triangle()
    d.g["bufferViews"][0]["byteLength"] = 400  # beyond the buffer
    g = d.embedded()
    g["buffers"][0]["byteLength"] = len(d.bin)
    write("view_oob.gltf", g)

    d = one_triangle()
    d.g["meshes"][0]["primitives"][0]["indices"] = d.indices([0, 1, 7])
    write("index_oob.gltf", d.embedded())

    d = one_triangle()
    nrm = d.accessor(f32(0, 0, 1, 0, 0, 1), FLOAT, "VEC3", 2)
    d.g["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = nrm
    write("normal_count.gltf", d.embedded())

    d = one_triangle()
    d.g["meshes"][0]["primitives"][0]["attributes"] = {"NORMAL": 0}
    write("no_position.gltf", d.embedded())

    d = one_triangle()
    d.accessor(struct.pack("<3H", 0, 0, 0) + b"\x00\x00", USHORT, "VEC3", 1)
    d.g["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 1
    write("position_type.gltf", d.embedded())

    d = one_triangle()
    d.g["nodes"] = [{"children": [1]}, {"children": [0], "mesh": 0}]
    d.g["scenes"] = [{"nodes": []}]
    write("cycle.gltf", d.embedded())

    d = one_triangle()
    d.g["cameras"] = [{"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 0, "znear": 0.1, "zfar": 10}}]
    write("ortho_zero.gltf", d.embedded())

    # Draco-compressed: the accessors carry no data of their own (tinygltf
    # refuses them); the required extension is the reason to report
    d = one_triangle()
    g = d.embedded()
    del g["accessors"][0]["bufferView"]
    g["extensionsUsed"] = g["extensionsRequired"] = ["KHR_draco_mesh_compression"]
    write("draco_required.gltf", g)

    d = one_triangle()
    d.g["nodes"] = [{"children": [2]}, {"children": [2]}, {"mesh": 0}]
    d.g["scenes"] = [{"nodes": [0, 1]}]
    write("two_parents.gltf", d.embedded())

    d = one_triangle()
    d.g["nodes"] = [{"children": [5]}]
    write("child_oob.gltf", d.embedded())

    d = one_triangle()
    d.g["nodes"] = [{"mesh": 3}]
    write("mesh_oob.gltf", d.embedded())

    d = one_triangle()
    d.g["meshes"][0]["primitives"][0]["material"] = 2
    write("material_oob.gltf", d.embedded())

    d = one_triangle()
    d.g["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 4}}}]
    d.g["meshes"][0]["primitives"][0]["material"] = 0
    write("texture_oob.gltf", d.embedded())

    d = one_triangle()
    d.g["extensionsRequired"] = ["KHR_draco_mesh_compression"]
    d.g["extensionsUsed"] = ["KHR_draco_mesh_compression"]
    write("required_ext.gltf", d.embedded())

    d = one_triangle()
    d.g["accessors"][0]["sparse"] = {"count": 1, "indices": {"bufferView": 0, "componentType": UBYTE},
                                     "values": {"bufferView": 0}}
    g = d.embedded()  # the sparse index (9) sits in a view of its own, past the 3 vertices
    sidx = len(d.bin)
    binary = d.bin + bytes([9, 0, 0, 0])
    g["bufferViews"].append({"buffer": 0, "byteOffset": sidx, "byteLength": 4})
    g["accessors"][0]["sparse"]["indices"]["bufferView"] = len(g["bufferViews"]) - 1
    g["buffers"] = [{"byteLength": len(binary), "uri": data_uri(binary)}]
    write("sparse_index_oob.gltf", g)


def quantized():
    """KHR_mesh_quantization (gltfpack's layout): POSITION as normalized
    SHORT in a byteStride-8 view, dequantised by the node's scale and
    translation; NORMAL as normalized BYTE (not unit length); TEXCOORD_0 as
    plain (not normalized) USHORT.  World triangle: (1,2,3), (3,2,3), (1,4,3)."""
    d = Doc()
    q = 32767
    pos = struct.pack("<4h", 0, 0, 0, 0) + struct.pack("<4h", q, 0, 0, 0) + struct.pack("<4h", 0, q, 0, 0)
    pv = d.view(pos, stride=8)
    d.g["accessors"].append({"bufferView": pv, "componentType": 5122, "normalized": True, "count": 3,
                             "type": "VEC3", "min": [0, 0, 0], "max": [q, q, 0]})
    posa = len(d.g["accessors"]) - 1
    nv = d.view(struct.pack("<12b", 0, 0, 64, 0, 0, 0, 64, 0, 0, 0, 64, 0), stride=4)
    d.g["accessors"].append({"bufferView": nv, "componentType": 5120, "normalized": True, "count": 3,
                             "type": "VEC3"})
    nrm = len(d.g["accessors"]) - 1
    uv = d.accessor(struct.pack("<6H", 0, 0, 2, 0, 0, 2), USHORT, "VEC2", 3)
    d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": posa, "NORMAL": nrm, "TEXCOORD_0": uv}}]}]
    d.g["nodes"] = [{"mesh": 0, "translation": [1, 2, 3], "scale": [2, 2, 2]}]
    d.g["scenes"] = [{"nodes": [0]}]
    d.g["extensionsUsed"] = ["KHR_mesh_quantization"]
    d.g["extensionsRequired"] = ["KHR_mesh_quantization"]
    write("quantized.gltf", d.embedded())


def texture_transform():
    """materials.gltf's first material with KHR_texture_transform on the
    base colour texture: offset (0.5, 0), rotation pi/2, scale (2, 1); the
    other slots untransformed."""
    d = Doc()
    pos = d.positions(TRI)
    uv = d.accessor(f32(0, 0, 1, 0, 0, 1), FLOAT, "VEC2", 3)
    d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv}, "material": 0}]}]
    d.g["nodes"] = [{"mesh": 0}]
    d.g["scenes"] = [{"nodes": [0]}]
    d.g["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(png(2, 2, PIXELS)).decode()}]
    d.g["textures"] = [{"source": 0}]
    d.g["materials"] = [
        {"pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": {
                "offset": [0.5, 0], "rotation": math.pi / 2, "scale": [2, 1]}}},
            "metallicRoughnessTexture": {"index": 0}}}]
    d.g["extensionsUsed"] = ["KHR_texture_transform"]
    write("texture_transform.gltf", d.embedded())
    bad = json.loads(json.dumps(d.g))
    bad["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]["KHR_texture_transform"][
        "scale"] = [1, "x"]
    write("texture_transform_bad.gltf", bad)


def texcoord1():
    """Two texture coordinate sets: the base colour texture reads
    TEXCOORD_1 (texCoord 1), the emissive one TEXCOORD_0, and the
    metallic-roughness one set 1 through KHR_texture_transform's texCoord."""
    d = Doc()
    pos = d.positions(TRI)
    uv0 = d.accessor(f32(0, 0, 1, 0, 0, 1), FLOAT, "VEC2", 3)
    uv1 = d.accessor(f32(0.25, 0.25, 0.75, 0.25, 0.25, 0.75), FLOAT, "VEC2", 3)
    d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv0, "TEXCOORD_1": uv1},
                                      "material": 0}]}]
    d.g["nodes"] = [{"mesh": 0}]
    d.g["scenes"] = [{"nodes": [0]}]
    d.g["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(png(2, 2, PIXELS)).decode()}]
    d.g["textures"] = [{"source": 0}]
    d.g["materials"] = [
        {"emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 0},
         "pbrMetallicRoughness": {
             "baseColorTexture": {"index": 0, "texCoord": 1},
             "metallicRoughnessTexture": {"index": 0, "extensions": {"KHR_texture_transform": {
                 "texCoord": 1, "scale": [1, 1]}}}}}]
    d.g["extensionsUsed"] = ["KHR_texture_transform"]
    write("texcoord1.gltf", d.embedded())
    bad = json.loads(json.dumps(d.embedded()))
    bad["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"]["extensions"][
        "KHR_texture_transform"]["texCoord"] = 1.5
    write("texcoord1_bad.gltf", bad)


def vertex_colors():
    """COLOR_0 three ways on the same triangle: VEC3 FLOAT (with a value
    above 1, clamped), VEC4 normalized USHORT, and none (white), under a
    material of base colour (0.5, 1, 1, 1)."""
    d = Doc()
    pos = d.positions(TRI)
    c3 = d.accessor(f32(1, 0, 0, 0, 1, 0, 0, 0, 2), FLOAT, "VEC3", 3)
    c4 = d.accessor(struct.pack("<12H", 65535, 65535, 65535, 32768, 0, 0, 0, 0, 65535, 0, 65535, 65535),
                    USHORT, "VEC4", 3, normalized=True)
    d.g["meshes"] = [{"primitives": [
        {"attributes": {"POSITION": pos, "COLOR_0": c3}, "material": 0},
        {"attributes": {"POSITION": pos, "COLOR_0": c4}, "material": 0},
        {"attributes": {"POSITION": pos}, "material": 0}]}]
    d.g["nodes"] = [{"mesh": 0}]
    d.g["scenes"] = [{"nodes": [0]}]
    d.g["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 1, 1, 1], "metallicFactor": 0}}]
    write("vertex_colors.gltf", d.embedded())


def floor_and_box(d):
    """A 6 x 6 floor and a 0.8 x 0.8 x 0.8 box on it: positions and indices."""
    fl = d.positions([(-3, 0, -3), (-3, 0, 3), (3, 0, 3), (3, 0, -3)])
    fi = d.indices([0, 1, 2, 0, 2, 3])
    s = 0.4
    box = [(-s, 0, -s), (s, 0, -s), (s, 0, s), (-s, 0, s), (-s, 0.8, -s), (s, 0.8, -s), (s, 0.8, s), (-s, 0.8, s)]
    bp = d.positions(box)
    bi = d.indices([4, 6, 5, 4, 7, 6, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7])
    return fl, fi, bp, bi


def panel_light():
    """A tessellated, tilted emissive panel (50 triangles, so shaft tests
    bound it by an oriented box) over a floor with a small box between,
    and a camera: the LIE oracle on an emitter of many triangles."""
    d = Doc()
    fl, fi, bp, bi = floor_and_box(d)
    n = 5
    c, sn = math.cos(0.4), math.sin(0.4)
    pts = []
    for i in range(n + 1):
        for j in range(n + 1):
            u, v = -0.8 + 1.6 * i / n, -0.8 + 1.6 * j / n
            pts.append((u, 2.2 + v * sn, v * c))
    idx = []
    for i in range(n):
        for j in range(n):
            a = i * (n + 1) + j
            b, e = a + 1, a + n + 1
            idx += [a, b, e, b, e + 1, e]
    pp = d.positions(pts)
    pi = d.indices(idx)
    d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": fl}, "indices": fi, "material": 0}]},
                     {"primitives": [{"attributes": {"POSITION": bp}, "indices": bi, "material": 0}]},
                     {"primitives": [{"attributes": {"POSITION": pp}, "indices": pi, "material": 1}]}]
    d.g["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0}},
                        {"emissiveFactor": [1, 0.9, 0.8], "doubleSided": True,
                         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 8}}}]
    d.g["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    d.g["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.05}}]
    d.g["nodes"] = [{"mesh": 0, "name": "Floor"}, {"mesh": 1, "name": "Box"}, {"mesh": 2, "name": "Panel"},
                    {"camera": 0, "translation": [0, 2.5, 5.5], "rotation": [-0.2588, 0, 0, 0.9659]}]
    d.g["scenes"] = [{"nodes": [0, 1, 2, 3]}]
    write("panel_light.gltf", d.embedded())


def light_strip():
    """A corridor lit by one long emissive strip of 80 triangles along its
    ceiling (facing down, one-sided), with three pillars and a low beam
    between strip and floor: an emitter that lie-build splits into clusters
    (lib/scene/cluster.c), whose pairs each see part of the strip."""
    d = Doc()
    fl = d.positions([(-4, 0, -1), (-4, 0, 1), (4, 0, 1), (4, 0, -1)])
    fi = d.indices([0, 1, 2, 0, 2, 3])
    wall = d.positions([(-4, 0, -1), (4, 0, -1), (4, 2.2, -1), (-4, 2.2, -1)])
    boxes = []
    for x, h in ((-2.0, 1.5), (0.3, 1.2), (2.2, 1.8)):
        s = 0.25
        boxes.append(d.positions([(x - s, 0, -s), (x + s, 0, -s), (x + s, 0, s), (x - s, 0, s),
                                  (x - s, h, -s), (x + s, h, -s), (x + s, h, s), (x - s, h, s)]))
    bi = d.indices([4, 6, 5, 4, 7, 6, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7])
    beam = d.positions([(-1.2, 1.6, -0.1), (-0.6, 1.6, -0.1), (-0.6, 1.6, 0.1), (-1.2, 1.6, 0.1)])
    n = 40
    pts = []
    for i in range(n + 1):
        x = -3.8 + 7.6 * i / n
        pts += [(x, 2.1, -0.15), (x, 2.1, 0.15)]
    idx = []
    for i in range(n):
        a = 2 * i
        idx += [a, a + 2, a + 1, a + 1, a + 2, a + 3]  # facing -y
    sp = d.positions(pts)
    si = d.indices(idx)
    d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": fl}, "indices": fi, "material": 0}]},
                     {"primitives": [{"attributes": {"POSITION": wall}, "indices": fi, "material": 0}]}]
    d.g["meshes"] += [{"primitives": [{"attributes": {"POSITION": b}, "indices": bi, "material": 0}]} for b in boxes]
    d.g["meshes"] += [{"primitives": [{"attributes": {"POSITION": beam}, "indices": fi, "material": 2}]},
                      {"primitives": [{"attributes": {"POSITION": sp}, "indices": si, "material": 1}]}]
    d.g["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0}},
                        {"emissiveFactor": [1, 0.95, 0.9],
                         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 6}}},
                        {"doubleSided": True,
                         "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.6, 1], "metallicFactor": 0}}]
    d.g["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    d.g["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.05}}]
    d.g["nodes"] = [{"mesh": 0, "name": "Floor"}, {"mesh": 1, "name": "Wall"},
                    {"mesh": 2, "name": "Pillar0"}, {"mesh": 3, "name": "Pillar1"}, {"mesh": 4, "name": "Pillar2"},
                    {"mesh": 5, "name": "Beam"}, {"mesh": 6, "name": "Strip"},
                    {"camera": 0, "translation": [0, 1.4, 3.6], "rotation": [-0.1305, 0, 0, 0.9914]}]
    d.g["scenes"] = [{"nodes": [0, 1, 2, 3, 4, 5, 6, 7]}]
    write("light_strip.gltf", d.embedded())


def dark_panel():
    """An emissive panel (8 x 2 quads facing down) whose 8 x 1 emissive
    texture is black in its left half, clamped, and beside it a second
    panel whose texture is black everywhere: a dark cluster
    (lib/scene/cluster.c) that no pair is built for; a box below casts a
    shadow from the lit half of the first."""
    d = Doc()
    fl, fi, bp, bi = floor_and_box(d)
    nx, nz = 8, 2
    pts, uvs = [], []
    for i in range(nx + 1):
        for j in range(nz + 1):
            pts.append((-2 + 4 * i / nx, 2.2, -0.5 + 1.0 * j / nz))
            uvs += [i / nx, j / nz]
    idx = []
    for i in range(nx):
        for j in range(nz):
            a = i * (nz + 1) + j
            b, e = a + 1, a + nz + 1
            idx += [a, e, b, b, e, e + 1]  # facing -y
    pp = d.positions(pts)
    pu = d.accessor(f32(*uvs), FLOAT, "VEC2", len(pts))
    pi = d.indices(idx)
    bp2 = d.positions([(-2, 2.2, 1.0), (2, 2.2, 1.0), (2, 2.2, 1.5), (-2, 2.2, 1.5)])
    bu2 = d.accessor(f32(0, 0, 1, 0, 1, 1, 0, 1), FLOAT, "VEC2", 4)
    bi2 = d.indices([0, 1, 2, 0, 2, 3])  # facing -y
    half = [[(0, 0, 0, 255)] * 4 + [(255, 255, 255, 255)] * 4]
    black = [[(0, 0, 0, 255)] * 2]
    d.g["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(png(8, 1, half)).decode()},
                     {"uri": "data:image/png;base64," + base64.b64encode(png(2, 1, black)).decode()}]
    d.g["samplers"] = [{"magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071}]
    d.g["textures"] = [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}]
    d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": fl}, "indices": fi, "material": 0}]},
                     {"primitives": [{"attributes": {"POSITION": bp}, "indices": bi, "material": 0}]},
                     {"primitives": [{"attributes": {"POSITION": pp, "TEXCOORD_0": pu}, "indices": pi,
                                      "material": 1}]},
                     {"primitives": [{"attributes": {"POSITION": bp2, "TEXCOORD_0": bu2}, "indices": bi2,
                                      "material": 2}]}]
    d.g["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0}},
                        {"emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 0},
                         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 8}}},
                        {"emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 1}}]
    d.g["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    d.g["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.05}}]
    d.g["nodes"] = [{"mesh": 0, "name": "Floor"}, {"mesh": 1, "name": "Box"}, {"mesh": 2, "name": "Panel"},
                    {"camera": 0, "translation": [0, 2.5, 5.5], "rotation": [-0.2588, 0, 0, 0.9659]},
                    {"mesh": 3, "name": "BlackPanel"}]
    d.g["scenes"] = [{"nodes": [0, 1, 2, 3, 4]}]
    write("dark_panel.gltf", d.embedded())


def alpha_mask():
    """alphaMode MASK: a floor, a light above it, and between them a screen
    whose 4x4 texture alternates solid and clear texels (cutoff 0.5), next
    to a quad whose base alpha 0.3 makes it clear everywhere; a camera."""
    d = Doc()
    fl = d.positions([(-3, 0, -3), (-3, 0, 3), (3, 0, 3), (3, 0, -3)])
    quad = d.indices([0, 1, 2, 0, 2, 3])
    scr = d.positions([(-1, 1, -1), (-1, 1, 1), (1, 1, 1), (1, 1, -1)])
    uv = d.accessor(f32(0, 0, 0, 1, 1, 1, 1, 0), FLOAT, "VEC2", 4)
    clear = d.positions([(1.5, 1, -1), (1.5, 1, 1), (2.5, 1, 1), (2.5, 1, -1)])
    lt = d.positions([(-0.5, 2.5, -0.5), (0.5, 2.5, -0.5), (0.5, 2.5, 0.5), (-0.5, 2.5, 0.5)])
    checker = [[(255, 255, 255, 255 if (i + j) % 2 == 0 else 0) for i in range(4)] for j in range(4)]
    d.g["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(png(4, 4, checker)).decode()}]
    d.g["samplers"] = [{"magFilter": 9728, "minFilter": 9728}]
    d.g["textures"] = [{"source": 0, "sampler": 0}]
    d.g["meshes"] = [
        {"primitives": [{"attributes": {"POSITION": fl}, "indices": quad, "material": 0}]},
        {"primitives": [{"attributes": {"POSITION": scr, "TEXCOORD_0": uv}, "indices": quad, "material": 1}]},
        {"primitives": [{"attributes": {"POSITION": clear}, "indices": quad, "material": 2}]},
        {"primitives": [{"attributes": {"POSITION": lt}, "indices": quad, "material": 3}]}]
    d.g["materials"] = [
        {"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0}},
        {"name": "screen", "alphaMode": "MASK", "doubleSided": True,
         "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0}},
        {"name": "clear", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": True,
         "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.3], "metallicFactor": 0}},
        {"emissiveFactor": [1, 1, 1], "doubleSided": True,
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10}}}]
    d.g["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    d.g["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.05}}]
    d.g["nodes"] = [{"mesh": 0, "name": "Floor"}, {"mesh": 1, "name": "Screen"}, {"mesh": 2, "name": "Clear"},
                    {"mesh": 3, "name": "Light"},
                    {"camera": 0, "translation": [0, 4.5, 4.5], "rotation": [-0.3827, 0, 0, 0.9239]}]
    d.g["scenes"] = [{"nodes": [0, 1, 2, 3, 4]}]
    write("alpha_mask.gltf", d.embedded())


def normal_map():
    """A floor (4 x 4, normals up, u along +x, v along +z) under a point
    light, with a box on it, its material's normalTexture an 8 x 8 map of
    grooves: columns alternately tilted toward +x and -x, the top rows also
    toward +y of texture space.  Written three ways: tangents computed
    (normal_map.gltf), the same tangents given as TANGENT
    (normal_map_tangent.gltf), and no normal map (normal_map_none.gltf)."""
    def tilt(x, y):
        z = math.sqrt(max(0.0, 1.0 - x * x - y * y))
        return tuple(int(round((c + 1) / 2 * 255)) for c in (x, y, z)) + (255,)
    grooves = [[tilt(0.5 if i % 2 == 0 else -0.5, 0.4 if j < 2 else 0.0) for i in range(8)] for j in range(8)]
    for variant in ("computed", "tangent", "none"):
        d = Doc()
        fl = d.positions([(-2, 0, -2), (-2, 0, 2), (2, 0, 2), (2, 0, -2)])
        fn = d.accessor(f32(*([0, 1, 0] * 4)), FLOAT, "VEC3", 4)
        fuv = d.accessor(f32(0, 0, 0, 1, 1, 1, 1, 0), FLOAT, "VEC2", 4)
        quad = d.indices([0, 1, 2, 0, 2, 3])
        s = 0.3
        box = [(-s, 0, -s), (s, 0, -s), (s, 0, s), (-s, 0, s), (-s, 0.6, -s), (s, 0.6, -s), (s, 0.6, s), (-s, 0.6, s)]
        bp = d.positions(box)
        bi = d.indices([4, 6, 5, 4, 7, 6, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7])
        attrs = {"POSITION": fl, "NORMAL": fn, "TEXCOORD_0": fuv}
        if variant == "tangent":
            attrs["TANGENT"] = d.accessor(f32(*([1, 0, 0, 1] * 4)), FLOAT, "VEC4", 4)
        floor = {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0,
                                          "roughnessFactor": 0.6}}
        if variant != "none":
            d.g["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(png(8, 8, grooves)).decode()}]
            d.g["samplers"] = [{"magFilter": 9728, "minFilter": 9728}]
            d.g["textures"] = [{"source": 0, "sampler": 0}]
            floor["normalTexture"] = {"index": 0, "scale": 0.9}
        d.g["meshes"] = [{"primitives": [{"attributes": attrs, "indices": quad, "material": 0}]},
                         {"primitives": [{"attributes": {"POSITION": bp}, "indices": bi, "material": 1}]}]
        d.g["materials"] = [floor, {"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.6, 0.7, 1],
                                                             "metallicFactor": 0}}]
        d.g["extensionsUsed"] = ["KHR_lights_punctual"]
        d.g["extensions"] = {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 6}]}}
        d.g["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.05}}]
        d.g["nodes"] = [{"mesh": 0, "name": "Floor"}, {"mesh": 1, "name": "Box"},
                        {"name": "Lamp", "translation": [0.4, 1.5, 0.3], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                        {"camera": 0, "translation": [0, 3, 3], "rotation": [-0.3827, 0, 0, 0.9239]}]
        d.g["scenes"] = [{"nodes": [0, 1, 2, 3]}]
        name = {"computed": "normal_map.gltf", "tangent": "normal_map_tangent.gltf", "none": "normal_map_none.gltf"}
        write(name[variant], d.embedded())


def glass_box():
    """A point light and a small emissive quad inside a closed box of
    coloured glass (KHR_materials_transmission, no volume: thin) on a
    floor, with an opaque post outside it; glass_box_opaque.gltf is the
    same box without transmission.  The floor outside is lit only through
    the glass, tinted by its base colour."""
    for variant in ("glass", "opaque"):
        d = Doc()
        fl = d.positions([(-3, 0, -3), (-3, 0, 3), (3, 0, 3), (3, 0, -3)])
        quad = d.indices([0, 1, 2, 0, 2, 3])
        s = 0.4
        box = [(-s, 0, -s), (s, 0, -s), (s, 0, s), (-s, 0, s), (-s, 0.8, -s), (s, 0.8, -s), (s, 0.8, s), (-s, 0.8, s)]
        bp = d.positions(box)
        bi = d.indices([4, 6, 5, 4, 7, 6, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7])
        post = d.positions([(1.0, 0, -0.1), (1.2, 0, -0.1), (1.2, 0, 0.1), (1.0, 0, 0.1),
                            (1.0, 1.0, -0.1), (1.2, 1.0, -0.1), (1.2, 1.0, 0.1), (1.0, 1.0, 0.1)])
        fil = d.positions([(-0.1, 0.45, -0.1), (0.1, 0.45, -0.1), (0.1, 0.45, 0.1), (-0.1, 0.45, 0.1)])
        glass = {"name": "glass", "doubleSided": True,
                 "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.5, 0.25, 1], "metallicFactor": 0,
                                          "roughnessFactor": 0.05}}
        if variant == "glass":
            glass["extensions"] = {"KHR_materials_transmission": {"transmissionFactor": 0.9}}
        d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": fl}, "indices": quad, "material": 0}]},
                         {"primitives": [{"attributes": {"POSITION": bp}, "indices": bi, "material": 1}]},
                         {"primitives": [{"attributes": {"POSITION": post}, "indices": bi, "material": 0}]},
                         {"primitives": [{"attributes": {"POSITION": fil}, "indices": quad, "material": 2}]}]
        d.g["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0}},
                            glass,
                            {"emissiveFactor": [1, 1, 1], "doubleSided": True,
                             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 20}}}]
        d.g["extensionsUsed"] = ["KHR_lights_punctual", "KHR_materials_emissive_strength"] + (
            ["KHR_materials_transmission"] if variant == "glass" else [])
        d.g["extensions"] = {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 3}]}}
        d.g["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.05}}]
        d.g["nodes"] = [{"mesh": 0, "name": "Floor"}, {"mesh": 1, "name": "Glass"}, {"mesh": 2, "name": "Post"},
                        {"mesh": 3, "name": "Filament"},
                        {"name": "Bulb", "translation": [0, 0.6, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                        {"camera": 0, "translation": [0, 3.5, 3.5], "rotation": [-0.3827, 0, 0, 0.9239]}]
        d.g["scenes"] = [{"nodes": [0, 1, 2, 3, 4, 5]}]
        write("glass_box.gltf" if variant == "glass" else "glass_box_opaque.gltf", d.embedded())


def fidelity():
    """What --write-scene must keep: a floor with a JPEG base colour
    (checker.jpg beside the file, written once by oiiotool), a normal map
    (PNG, scale 0.9, KHR_texture_transform) and TANGENT, and an
    occlusionTexture, which is not read; a glass box
    (KHR_materials_transmission with a texture) holding a point light
    (KHR_lights_punctual) and an emissive quad
    (KHR_materials_emissive_strength)."""
    def tilt(x, y):
        z = math.sqrt(max(0.0, 1.0 - x * x - y * y))
        return tuple(int(round((c + 1) / 2 * 255)) for c in (x, y, z)) + (255,)
    grooves = [[tilt(0.5 if i % 2 == 0 else -0.5, 0.0) for i in range(4)] for j in range(4)]
    d = Doc()
    fl = d.positions([(-2, 0, -2), (-2, 0, 2), (2, 0, 2), (2, 0, -2)])
    fn = d.accessor(f32(*([0, 1, 0] * 4)), FLOAT, "VEC3", 4)
    ft = d.accessor(f32(*([1, 0, 0, 1] * 4)), FLOAT, "VEC4", 4)
    fuv = d.accessor(f32(0, 0, 0, 1, 1, 1, 1, 0), FLOAT, "VEC2", 4)
    quad = d.indices([0, 1, 2, 0, 2, 3])
    s = 0.4
    box = [(-s, 0, -s), (s, 0, -s), (s, 0, s), (-s, 0, s), (-s, 0.8, -s), (s, 0.8, -s), (s, 0.8, s), (-s, 0.8, s)]
    bp = d.positions(box)
    buv = d.accessor(f32(0, 0, 1, 0, 1, 1, 0, 1, 0, 0, 1, 0, 1, 1, 0, 1), FLOAT, "VEC2", 8)
    bi = d.indices([4, 6, 5, 4, 7, 6, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7])
    fil = d.positions([(-0.1, 0.45, -0.1), (0.1, 0.45, -0.1), (0.1, 0.45, 0.1), (-0.1, 0.45, 0.1)])
    d.g["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(png(4, 4, grooves)).decode()},
                     {"uri": "checker.jpg", "name": "checker"}]
    d.g["samplers"] = [{"wrapS": 33648, "wrapT": 10497}]
    d.g["textures"] = [{"source": 0}, {"source": 1, "sampler": 0}]
    d.g["meshes"] = [
        {"primitives": [{"attributes": {"POSITION": fl, "NORMAL": fn, "TANGENT": ft, "TEXCOORD_0": fuv},
                         "indices": quad, "material": 0}]},
        {"primitives": [{"attributes": {"POSITION": bp, "TEXCOORD_0": buv}, "indices": bi, "material": 1}]},
        {"primitives": [{"attributes": {"POSITION": fil}, "indices": quad, "material": 2}]}]
    d.g["materials"] = [
        {"name": "floor",
         "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}, "metallicFactor": 0, "roughnessFactor": 0.7},
         "normalTexture": {"index": 0, "scale": 0.9,
                           "extensions": {"KHR_texture_transform": {"scale": [2, 2], "rotation": 0.5}}},
         "occlusionTexture": {"index": 0}},
        {"name": "glass", "doubleSided": True,
         "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.5, 0.25, 1], "metallicFactor": 0,
                                  "roughnessFactor": 0.05},
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.9,
                                                       "transmissionTexture": {"index": 0, "texCoord": 0}}}},
        {"emissiveFactor": [1, 0.9, 0.8], "doubleSided": True,
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 20}}}]
    d.g["extensionsUsed"] = ["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_transmission",
                             "KHR_texture_transform"]
    d.g["extensions"] = {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 3, "color": [1, 0.9, 0.7]}]}}
    d.g["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.05}}]
    d.g["nodes"] = [{"mesh": 0, "name": "Floor"}, {"mesh": 1, "name": "Glass"}, {"mesh": 2, "name": "Filament"},
                    {"name": "Bulb", "translation": [0, 0.6, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                    {"camera": 0, "translation": [0, 3.5, 3.5], "rotation": [-0.3827, 0, 0, 0.9239]}]
    d.g["scenes"] = [{"nodes": [0, 1, 2, 3, 4]}]
    write("fidelity.gltf", d.embedded())


def bent_light():
    """A bent emitter (two quads meeting at 40 degrees: not planar, so
    lie-render tests its blockers in 3D) and a spot light, over a floor
    with a box and a tilted quad between; a perspective and an orthographic
    camera: the LIE oracle off the planar-emitter path."""
    d = Doc()
    fl = d.positions([(-3, 0, -3), (-3, 0, 3), (3, 0, 3), (3, 0, -3)])
    quad = d.indices([0, 1, 2, 0, 2, 3])
    s = 0.35
    box = [(-s, 0, -s), (s, 0, -s), (s, 0, s), (-s, 0, s), (-s, 0.7, -s), (s, 0.7, -s), (s, 0.7, s), (-s, 0.7, s)]
    bp = d.positions([(x - 0.6, y, z) for x, y, z in box])
    bi = d.indices([4, 6, 5, 4, 7, 6, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7])
    tilt = d.positions([(0.3, 1.3, -0.5), (0.3, 0.8, 0.5), (1.1, 0.8, 0.5), (1.1, 1.3, -0.5)])
    c, sn = math.cos(math.radians(20)), math.sin(math.radians(20))
    lt = d.positions([(-0.8 * c, 2.2 + 0.8 * sn, -0.5), (0, 2.2, -0.5), (0, 2.2, 0.5), (-0.8 * c, 2.2 + 0.8 * sn, 0.5),
                      (0.8 * c, 2.2 + 0.8 * sn, -0.5), (0.8 * c, 2.2 + 0.8 * sn, 0.5)])
    li = d.indices([0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2])
    d.g["meshes"] = [{"primitives": [{"attributes": {"POSITION": fl}, "indices": quad, "material": 0}]},
                     {"primitives": [{"attributes": {"POSITION": bp}, "indices": bi, "material": 0}]},
                     {"primitives": [{"attributes": {"POSITION": tilt}, "indices": quad, "material": 1}]},
                     {"primitives": [{"attributes": {"POSITION": lt}, "indices": li, "material": 2}]}]
    d.g["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0}},
                        {"doubleSided": True,
                         "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.6, 0.7, 1], "metallicFactor": 0}},
                        {"emissiveFactor": [1, 0.95, 0.9], "doubleSided": True,
                         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 6}}}]
    d.g["extensionsUsed"] = ["KHR_materials_emissive_strength", "KHR_lights_punctual"]
    d.g["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"type": "spot", "color": [0.8, 0.9, 1], "intensity": 12, "spot": {"outerConeAngle": 0.7}}]}}
    d.g["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.05}},
                      {"type": "orthographic", "name": "Plan",
                       "orthographic": {"xmag": 3.2, "ymag": 2.4, "znear": 0.01, "zfar": 50}}]
    d.g["nodes"] = [{"mesh": 0, "name": "Floor"}, {"mesh": 1, "name": "Box"}, {"mesh": 2, "name": "Tilted"},
                    {"mesh": 3, "name": "BentLight"},
                    {"name": "Spot", "translation": [1.5, 2.5, 1.0], "rotation": [-0.7071, 0, 0, 0.7071],
                     "extensions": {"KHR_lights_punctual": {"light": 0}}},
                    {"camera": 0, "translation": [0, 2.8, 5.0], "rotation": [-0.2588, 0, 0, 0.9659]},
                    {"camera": 1, "name": "Top", "translation": [0, 1.9, 3.0], "rotation": [-0.3827, 0, 0, 0.9239]}]
    d.g["scenes"] = [{"nodes": [0, 1, 2, 3, 4, 5, 6]}]
    write("bent_light.gltf", d.embedded())


def morph():
    """The quad with two morph targets: target 0 lifts every vertex by 1 in
    z (a sparse accessor with no bufferView), target 1 moves vertex 3 by 1 in
    x and tilts its normal.  The mesh's weights are [0.5, 0]; node "Half"
    uses them, node "Full" has its own [1, 1], node "Rest" [0, 0].  Also
    morph_bad.gltf: a node with one weight for the two targets."""
    d = Doc()
    pos = d.positions(QUAD)
    nrm = d.accessor(f32(*[0, 0, 1] * 4), FLOAT, "VEC3", 4)
    idx = d.indices([0, 1, 2, 2, 1, 3])
    lift_idx = d.view(struct.pack("<4H", 0, 1, 2, 3))
    lift_val = d.view(f32(*[0, 0, 1] * 4))
    d.g["accessors"].append({"componentType": FLOAT, "count": 4, "type": "VEC3",
                             "sparse": {"count": 4, "indices": {"bufferView": lift_idx, "componentType": USHORT},
                                        "values": {"bufferView": lift_val}}})
    lift = len(d.g["accessors"]) - 1
    push = d.accessor(f32(*([0, 0, 0] * 3 + [1, 0, 0])), FLOAT, "VEC3", 4, min=[0, 0, 0], max=[1, 0, 0])
    tilt = d.accessor(f32(*([0, 0, 0] * 3 + [1, 0, -1])), FLOAT, "VEC3", 4)
    d.g["meshes"] = [{"name": "Sheet", "weights": [0.5, 0],
                      "primitives": [{"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx,
                                      "targets": [{"POSITION": lift}, {"POSITION": push, "NORMAL": tilt}]}]}]
    d.g["nodes"] = [{"name": "Half", "mesh": 0},
                    {"name": "Full", "mesh": 0, "weights": [1, 1], "translation": [3, 0, 0]},
                    {"name": "Rest", "mesh": 0, "weights": [0, 0], "translation": [6, 0, 0]}]
    d.g["scenes"] = [{"nodes": [0, 1, 2]}]
    d.g["scene"] = 0
    g = d.embedded()
    write("morph.gltf", g)
    bad = json.loads(json.dumps(g))
    bad["nodes"][1]["weights"] = [1]
    write("morph_bad.gltf", bad)
    # morph_lit.gltf: the three sheets lit by a square light 3 above them
    # (facing them) in front of a wall 1 behind them (tests/tools/t0400:
    # update = rebuild when morph weights push a sheet out to huge
    # coordinates)
    lit = json.loads(json.dumps(g))
    lit["materials"] = [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0}},
                        {"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}, "emissiveFactor": [1, 1, 1]}]
    sheet = lit["meshes"][0]["primitives"][0]
    sheet["material"] = 0
    plain = {"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx}
    lit["meshes"].append({"name": "Wall", "primitives": [dict(plain, material=0)]})
    lit["meshes"].append({"name": "Panel", "primitives": [dict(plain, material=1)]})
    lit["nodes"].append({"name": "Wall", "mesh": 1, "translation": [-2, -2, -1], "scale": [12, 6, 1]})
    lit["nodes"].append({"name": "Lamp", "mesh": 2, "translation": [1, 2, 3], "rotation": [1, 0, 0, 0],
                         "scale": [6, 2, 1]})
    lit["scenes"] = [{"nodes": [0, 1, 2, 3, 4]}]
    write("morph_lit.gltf", lit)


def animated():
    """Animations (glTF 2.0 §3.11) for lie-animate: keys from t = 0.5 s.
    "Slider" translates LINEAR, "Spinner" rotates LINEAR (slerp, 0 -> 90 ->
    180 degrees about y), "Pulser" scales CUBICSPLINE, "Stepper" translates
    STEP, "Sheet" morphs (one target, weights LINEAR), "Bone1" bends the
    skinned "Arm" (two joints), "Bulb" (a point light) and "Cam" (the
    camera) move, and "Offstage" (not in the default scene) moves too.  A
    second animation "Idle" turns the spinner only.  Also the malformed
    anim_bad_*.gltf, one defect each."""
    d = Doc()
    fl = d.positions([(-3, 0, -3), (-3, 0, 3), (3, 0, 3), (3, 0, -3)])
    quad = d.indices([0, 1, 2, 0, 2, 3])
    s = 0.25
    box = [(-s, 0, -s), (s, 0, -s), (s, 0, s), (-s, 0, s), (-s, 2 * s, -s), (s, 2 * s, -s), (s, 2 * s, s),
           (-s, 2 * s, s)]
    bp = d.positions(box)
    bi = d.indices([4, 6, 5, 4, 7, 6, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7])
    lt = d.positions([(-0.5, 2.5, -0.5), (0.5, 2.5, -0.5), (0.5, 2.5, 0.5), (-0.5, 2.5, 0.5)])
    ltn = d.accessor(f32(*[0, -1, 0] * 4), FLOAT, "VEC3", 4)
    # the sheet: a horizontal quad at y = 0.6 whose target lifts two corners
    sh = d.positions([(-0.4, 0.6, -0.4), (-0.4, 0.6, 0.4), (0.4, 0.6, 0.4), (0.4, 0.6, -0.4)])
    lift = d.accessor(f32(0, 0, 0, 0, 0, 0, 0, 0.5, 0, 0, 0.5, 0), FLOAT, "VEC3", 4)
    # the arm: a vertical ribbon at x = 1.8, rows at y = 0, 0.5, 1
    ax, az = 1.8, -1.2
    arm = [(ax - 0.15, y, az) for y in (0, 0.5, 1)] + [(ax + 0.15, y, az) for y in (0, 0.5, 1)]
    ap = d.positions(arm)
    ai = d.indices([0, 3, 1, 1, 3, 4, 1, 4, 2, 2, 4, 5])
    joints = d.accessor(bytes([0, 1, 0, 0] * 6), UBYTE, "VEC4", 6)
    w = []
    for k in range(6):
        row = k % 3
        w += [1, 0, 0, 0] if row == 0 else [0.5, 0.5, 0, 0] if row == 1 else [0, 1, 0, 0]
    weights = d.accessor(f32(*w), FLOAT, "VEC4", 6)
    ibm = d.accessor(f32(*[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -ax, 0, -az, 1],
                         *[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -ax, -0.5, -az, 1]), FLOAT, "MAT4", 2)
    d.g["meshes"] = [
        {"name": "Floor", "primitives": [{"attributes": {"POSITION": fl}, "indices": quad, "material": 0}]},
        {"name": "Box", "primitives": [{"attributes": {"POSITION": bp}, "indices": bi, "material": 0}]},
        {"name": "Light", "primitives": [{"attributes": {"POSITION": lt, "NORMAL": ltn}, "indices": quad,
                                          "material": 1}]},
        {"name": "Sheet", "weights": [0], "primitives": [{"attributes": {"POSITION": sh}, "indices": quad,
                                                          "material": 0, "targets": [{"POSITION": lift}]}]},
        {"name": "Arm", "primitives": [{"attributes": {"POSITION": ap, "JOINTS_0": joints, "WEIGHTS_0": weights},
                                        "indices": ai, "material": 2}]}]
    d.g["materials"] = [
        {"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0}},
        {"emissiveFactor": [1, 0.95, 0.9], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10}}},
        {"doubleSided": True, "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.4, 0.2, 1], "metallicFactor": 0}}]
    d.g["extensionsUsed"] = ["KHR_materials_emissive_strength", "KHR_lights_punctual"]
    d.g["extensions"] = {"KHR_lights_punctual": {"lights": [{"type": "point", "name": "bulb", "intensity": 2,
                                                            "color": [1, 0.8, 0.6]}]}}
    d.g["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.05}}]
    d.g["skins"] = [{"name": "ArmSkin", "joints": [7, 8], "inverseBindMatrices": ibm}]
    d.g["nodes"] = [
        {"name": "Floor", "mesh": 0},                                       # 0
        {"name": "Light", "mesh": 2},                                       # 1
        {"name": "Slider", "mesh": 1, "translation": [-1.5, 0, 0]},         # 2
        {"name": "Spinner", "mesh": 1, "translation": [0, 0, -1]},          # 3
        {"name": "Pulser", "mesh": 1, "translation": [1, 0, 1]},            # 4
        {"name": "Stepper", "mesh": 1, "translation": [-1, 0, 1.5]},        # 5
        {"name": "Sheet", "mesh": 3, "translation": [0.8, 0, -0.2]},        # 6
        {"name": "Bone0", "translation": [ax, 0, az], "children": [8]},     # 7
        {"name": "Bone1", "translation": [0, 0.5, 0]},                      # 8
        {"name": "Arm", "mesh": 4, "skin": 0},                              # 9
        {"name": "Bulb", "translation": [-2, 1.5, -2],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},              # 10
        {"name": "Cam", "camera": 0, "translation": [0, 3.5, 5], "rotation": [-0.2588, 0, 0, 0.9659]},  # 11
        {"name": "Offstage", "mesh": 1}]                                    # 12
    d.g["scenes"] = [{"nodes": [0, 1, 2, 3, 4, 5, 6, 7, 9, 10, 11]}, {"nodes": [12]}]
    d.g["scene"] = 0

    def acc(vals, type_):
        n = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[type_]
        extra = {}
        if type_ == "SCALAR":
            extra = {"min": [min(vals)], "max": [max(vals)]}
        return d.accessor(f32(*vals), FLOAT, type_, len(vals) // n, **extra)

    t3 = acc([0.5, 1.5, 2.5], "SCALAR")
    t2 = acc([0.5, 2.5], "SCALAR")
    t4 = acc([0.5, 1.0, 1.5, 2.0], "SCALAR")
    r = math.sqrt(0.5)
    samplers = [
        {"input": t3, "output": acc([-1.5, 0, 0, -1.5, 0, 1, -0.5, 0, 1], "VEC3")},                     # 0 Slider
        {"input": t3, "output": acc([0, 0, 0, 1, 0, r, 0, r, 0, 1, 0, 0], "VEC4")},                     # 1 Spinner
        {"input": t3, "interpolation": "CUBICSPLINE",                                                    # 2 Pulser
         "output": acc([0, 0, 0, 1, 1, 1, 0, 1, 0,
                        0, 1, 0, 1, 1.6, 1, 0, -1, 0,
                        0, -1, 0, 1, 1, 1, 0, 0, 0], "VEC3")},
        {"input": t4, "interpolation": "STEP",                                                            # 3 Stepper
         "output": acc([-1, 0, 1.5, -1, 0, 0.8, -1.6, 0, 0.8, -1.6, 0, 1.5], "VEC3")},
        {"input": t3, "output": acc([0, 1, 0.2], "SCALAR")},                                              # 4 Sheet
        {"input": t3, "output": acc([0, 0, 0, 1, 0, 0, 0.3827, 0.9239, 0, 0, -0.3827, 0.9239], "VEC4")},  # 5 Bone1
        {"input": t2, "output": acc([-2, 1.5, -2, 2, 1.5, -2], "VEC3")},                                  # 6 Bulb
        {"input": t2, "output": acc([0, 3.5, 5, 0.8, 3.0, 4.5], "VEC3")},                                 # 7 Cam
        {"input": t2, "output": acc([0, 0, 0, 0, 1, 0], "VEC3")},                                         # 8 Offstage
    ]
    chans = [(0, 2, "translation"), (1, 3, "rotation"), (2, 4, "scale"), (3, 5, "translation"),
             (4, 6, "weights"), (5, 8, "rotation"), (6, 10, "translation"), (7, 11, "translation"),
             (8, 12, "translation")]
    d.g["animations"] = [
        {"name": "Show", "samplers": samplers,
         "channels": [{"sampler": a, "target": {"node": n, "path": p}} for a, n, p in chans]},
        {"name": "Idle", "samplers": [{"input": t3, "output": samplers[1]["output"]}],
         "channels": [{"sampler": 0, "target": {"node": 3, "path": "rotation"}}]}]
    g = d.embedded()
    write("animated.gltf", g)

    def bad(name, change):
        b = json.loads(json.dumps(g))
        change(b)
        write(name, b)

    # an animated asset with no camera (a character, say): examples/animate frames it as
    # lie-render frames a scene without a camera
    def no_camera(b):
        del b["cameras"]
        del b["nodes"][11]["camera"]
    bad("animated_nocamera.gltf", no_camera)
    bad("anim_bad_count.gltf", lambda b: b["animations"][0]["samplers"][7].update(input=t3))
    bad("anim_bad_node.gltf", lambda b: b["animations"][0]["channels"][0]["target"].update(node=99))
    bad("anim_bad_path.gltf", lambda b: b["animations"][0]["channels"][0]["target"].update(path="position"))
    # input times 0.5, 1.5, 1.0: the Slider's keys out of order
    def unordered(b):
        d2 = Doc()
        d2.bin = base64.b64decode(b["buffers"][0]["uri"].split(",", 1)[1])
        d2.g = b
        t = d2.accessor(f32(0.5, 1.5, 1.0), FLOAT, "SCALAR", 3, min=[0.5], max=[1.5])
        b["animations"][0]["samplers"][0]["input"] = t
        b["buffers"] = [{"byteLength": len(d2.bin), "uri": data_uri(d2.bin)}]
    bad("anim_bad_input.gltf", unordered)


def main():
    normal_map()
    glass_box()
    fidelity()
    animated()
    morph()
    texcoord1()
    bent_light()
    alpha_mask()
    panel_light()
    light_strip()
    dark_panel()
    vertex_colors()
    quantized()
    texture_transform()
    modes()
    indices()
    hierarchy()
    no_scene()
    materials()
    lights_cameras()
    sparse()
    binary()
    external()
    limits()
    bad()


if __name__ == "__main__":
    main()
