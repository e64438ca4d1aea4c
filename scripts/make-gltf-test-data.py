#!/usr/bin/env python3
"""Writes the small glTF models of tests/data/gltf/ (standard library only).

    python3 scripts/make-gltf-test-data.py

Every buffer and image is embedded (base64 data URIs, or the GLB binary
chunk), so each model is one self-contained file:

- nodes.gltf: a triangle placed by two nodes under a transformed parent
  (TRS and matrix), its positions and normals interleaved (stride 24) and
  its UVs normalized unsigned shorts; two cameras (perspective,
  orthographic) and the three punctual light kinds.
- materials.gltf: a quad with six primitives, one per material: textures
  and factors, a normal map (no TANGENT: MikkTSpace), emission with
  emissive strength, MASK, BLEND, and transmission, IOR, volume and clear
  coat.
- emissive_quad.glb: an emissive quad filling the camera's view, lit by a
  directional light of intensity 0 (so no default environment).
- textured_quad.gltf: a quad filling the view with a 2 × 2 base colour
  texture (red, green / blue, white), nearest filtering, lit by the
  default environment.
- ortho_quad.gltf: the emissive quad [-1, 1]² seen 7 units away by an
  orthographic camera of xmag 2, ymag 1 (the quad covers the middle half
  of the image's width and all of its height).
"""

import base64
import json
import math
import os
import struct
import zlib

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "gltf")


def png(width, height, rows):
    """An 8-bit RGBA PNG of `rows` (lists of (r, g, b, a) tuples)."""

    def chunk(kind, data):
        c = kind + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + bytes(v for px in row for v in px) for row in rows)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


def data_uri(mime, data):
    return "data:%s;base64,%s" % (mime, base64.b64encode(data).decode())


def floats(values):
    return struct.pack("<%df" % len(values), *values)


def quad_buffer():
    """Positions, normals, UVs (v = 0 at the top) and indices of the quad [-1, 1]² at z = 0, facing +z."""
    pos = [-1, 1, 0, 1, 1, 0, 1, -1, 0, -1, -1, 0]
    nrm = [0, 0, 1] * 4
    uv = [0, 0, 1, 0, 1, 1, 0, 1]
    idx = struct.pack("<6H", 0, 3, 2, 0, 2, 1) + b"\x00\x00"
    data = floats(pos) + floats(nrm) + floats(uv) + idx
    views = [
        {"buffer": 0, "byteOffset": 0, "byteLength": 48},
        {"buffer": 0, "byteOffset": 48, "byteLength": 48},
        {"buffer": 0, "byteOffset": 96, "byteLength": 32},
        {"buffer": 0, "byteOffset": 128, "byteLength": 12},
    ]
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
        {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
        {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"},
    ]
    return data, views, accessors


QUAD_ATTRIBUTES = {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}


def write(name, doc):
    with open(os.path.join(OUT, name), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def nodes():
    # Interleaved position + normal (stride 24), then UVs as normalized u16, then u16 indices.
    verts = [((0, 0, 0), (0, 0, 1)), ((1, 0, 0), (0, 0, 1)), ((0, 1, 0), (0, 0, 1))]
    inter = b"".join(floats(list(p) + list(n)) for p, n in verts)
    uvs = struct.pack("<6H", 0, 0, 65535, 0, 0, 32768)
    idx = struct.pack("<3H", 0, 1, 2) + b"\x00\x00"
    data = inter + uvs + b"\x00\x00\x00\x00" + idx
    s = math.sqrt(0.5)
    doc = {
        "asset": {"version": "2.0", "generator": "caustic scripts/make-gltf-test-data.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "buffers": [{"byteLength": len(data), "uri": data_uri("application/octet-stream", data)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 72, "byteStride": 24},
            {"buffer": 0, "byteOffset": 72, "byteLength": 12},
            {"buffer": 0, "byteOffset": 88, "byteLength": 6},
        ],
        "accessors": [
            {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "normalized": True, "count": 3, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"},
        ],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3}]}],
        "cameras": [
            {"name": "persp", "type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.05}},
            {"name": "ortho", "type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}},
        ],
        "extensions": {
            "KHR_lights_punctual": {
                "lights": [
                    {"type": "directional", "color": [1, 0.5, 0.25], "intensity": 683},
                    {"type": "point", "intensity": 2732},
                    {"type": "spot", "intensity": 683, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
                ]
            }
        },
        "nodes": [
            {"name": "parent", "translation": [1, 2, 3], "rotation": [0, s, 0, s], "scale": [2, 2, 2], "children": [1, 2]},
            {"name": "childA", "mesh": 0, "translation": [0, 0, -1]},
            {"name": "childB", "mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 0, 0, 1]},
            {"name": "eye", "camera": 0, "translation": [0, 0, 10]},
            {"name": "sun", "rotation": [-s, 0, 0, s], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "lamp", "translation": [0, 4, 0], "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"name": "spot", "translation": [0, 0, 5], "extensions": {"KHR_lights_punctual": {"light": 2}}},
            {"name": "side", "camera": 1, "translation": [10, 0, 0], "rotation": [0, s, 0, s]},
        ],
        "scenes": [{"nodes": [0, 3, 4, 5, 6, 7]}],
        "scene": 0,
    }
    write("nodes.gltf", doc)


def materials():
    data, views, accessors = quad_buffer()
    base = png(2, 2, [[(255, 0, 0, 255), (0, 255, 0, 128)], [(0, 0, 255, 255), (255, 255, 255, 0)]])
    mr = png(1, 1, [[(0, 128, 255, 255)]])
    normal = png(1, 1, [[(128, 128, 255, 255)]])
    tex = lambda i, **kw: dict({"index": i}, **kw)
    mats = [
        {
            "name": "textured",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.5, 0.5, 0.5, 1],
                "baseColorTexture": tex(0, extensions={"KHR_texture_transform": {"offset": [0.5, 0], "rotation": 0.5, "scale": [2, 3]}}),
                "metallicFactor": 0.3,
                "roughnessFactor": 0.6,
                "metallicRoughnessTexture": tex(1),
            },
            "occlusionTexture": tex(1),
        },
        {"name": "bumpy", "normalTexture": {"index": 2, "scale": 0.5}},
        {
            "name": "glowing",
            "emissiveFactor": [1, 0.5, 0.25],
            "emissiveTexture": tex(0),
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}},
        },
        {"name": "masked", "alphaMode": "MASK", "alphaCutoff": 0.3, "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.8]}},
        {"name": "blended", "alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 0.25], "baseColorTexture": tex(0)}},
        {
            "name": "glass",
            "pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0.1},
            "extensions": {
                "KHR_materials_transmission": {"transmissionFactor": 0.9},
                "KHR_materials_ior": {"ior": 1.4},
                "KHR_materials_volume": {"thicknessFactor": 1, "attenuationDistance": 2, "attenuationColor": [0.5, 0.25, 1]},
                "KHR_materials_clearcoat": {"clearcoatFactor": 0.7, "clearcoatRoughnessFactor": 0.2, "clearcoatTexture": tex(1)},
            },
        },
    ]
    doc = {
        "asset": {"version": "2.0", "generator": "caustic scripts/make-gltf-test-data.py"},
        "extensionsUsed": [
            "KHR_texture_transform",
            "KHR_materials_emissive_strength",
            "KHR_materials_transmission",
            "KHR_materials_ior",
            "KHR_materials_volume",
            "KHR_materials_clearcoat",
        ],
        "buffers": [{"byteLength": len(data), "uri": data_uri("application/octet-stream", data)}],
        "bufferViews": views,
        "accessors": accessors,
        "images": [
            {"uri": data_uri("image/png", base)},
            {"uri": data_uri("image/png", mr)},
            {"uri": data_uri("image/png", normal)},
        ],
        "samplers": [{"magFilter": 9728, "wrapS": 33071, "wrapT": 33648}],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1}, {"source": 2}],
        "materials": mats,
        "meshes": [{"primitives": [{"attributes": QUAD_ATTRIBUTES, "indices": 3, "material": i} for i in range(len(mats))]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    }
    write("materials.gltf", doc)


def camera_node():
    # 3 units in front of the quad, a field of view narrower than the quad's.
    return {"camera": 0, "translation": [0, 0, 3]}


def emissive_quad():
    data, views, accessors = quad_buffer()
    doc = {
        "asset": {"version": "2.0", "generator": "caustic scripts/make-gltf-test-data.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength", "KHR_lights_punctual"],
        "buffers": [{"byteLength": len(data)}],
        "bufferViews": views,
        "accessors": accessors,
        "materials": [
            {
                "name": "sign",
                "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0, "roughnessFactor": 1},
                "emissiveFactor": [1, 0.5, 0.25],
                "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2}},
            }
        ],
        "meshes": [{"primitives": [{"attributes": QUAD_ATTRIBUTES, "indices": 3, "material": 0}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "aspectRatio": 1, "znear": 0.01}}],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 0}]}},
        "nodes": [{"mesh": 0}, camera_node(), {"extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "scenes": [{"nodes": [0, 1, 2]}],
    }
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    data += b"\x00" * (-len(data) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(data), 0x004E4942) + data
    glb = b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body
    with open(os.path.join(OUT, "emissive_quad.glb"), "wb") as f:
        f.write(glb)


def textured_quad():
    data, views, accessors = quad_buffer()
    image = png(2, 2, [[(255, 0, 0, 255), (0, 255, 0, 255)], [(0, 0, 255, 255), (255, 255, 255, 255)]])
    doc = {
        "asset": {"version": "2.0", "generator": "caustic scripts/make-gltf-test-data.py"},
        "buffers": [{"byteLength": len(data), "uri": data_uri("application/octet-stream", data)}],
        "bufferViews": views,
        "accessors": accessors,
        "images": [{"uri": data_uri("image/png", image)}],
        "samplers": [{"magFilter": 9728, "wrapS": 33071, "wrapT": 33071}],
        "textures": [{"source": 0, "sampler": 0}],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0, "roughnessFactor": 1}}
        ],
        "meshes": [{"primitives": [{"attributes": QUAD_ATTRIBUTES, "indices": 3, "material": 0}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "aspectRatio": 1, "znear": 0.01}}],
        "nodes": [{"mesh": 0}, camera_node()],
        "scenes": [{"nodes": [0, 1]}],
    }
    write("textured_quad.gltf", doc)


def ortho_quad():
    data, views, accessors = quad_buffer()
    doc = {
        "asset": {"version": "2.0", "generator": "caustic scripts/make-gltf-test-data.py"},
        "buffers": [{"byteLength": len(data), "uri": data_uri("application/octet-stream", data)}],
        "bufferViews": views,
        "accessors": accessors,
        "materials": [
            {
                "name": "sign",
                "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0, "roughnessFactor": 1},
                "emissiveFactor": [1, 0.5, 0.25],
            }
        ],
        "meshes": [{"primitives": [{"attributes": QUAD_ATTRIBUTES, "indices": 3, "material": 0}]}],
        "cameras": [
            {
                "name": "plan",
                "type": "orthographic",
                "orthographic": {"xmag": 2, "ymag": 1, "znear": 0.5, "zfar": 100},
            }
        ],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 0}]}},
        "nodes": [
            {"mesh": 0},
            {"camera": 0, "translation": [0, 0, 7]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}},
        ],
        "scenes": [{"nodes": [0, 1, 2]}],
    }
    write("ortho_quad.gltf", doc)


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    nodes()
    materials()
    emissive_quad()
    textured_quad()
    ortho_quad()
