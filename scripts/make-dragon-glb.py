#!/usr/bin/env python3
"""Writes the Stanford dragon (an ASCII PLY, optionally gzipped) as a GLB:
one mesh of POSITION, smooth NORMAL (area-weighted vertex normals) and
32-bit indices, a grey rough material, a perspective camera in front of it
and a directional light. A large glTF model for load and viewer timings.

    scripts/make-dragon-glb.py dragon_vrip.ply.gz dragon.glb
"""
import gzip
import json
import struct
import sys

import numpy as np


def read_ply(path):
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt") as f:
        nv = nf = 0
        for line in f:
            w = line.split()
            if w[:2] == ["element", "vertex"]:
                nv = int(w[2])
            elif w[:2] == ["element", "face"]:
                nf = int(w[2])
            elif w and w[0] == "end_header":
                break
        v = np.loadtxt(f, max_rows=nv, dtype=np.float32)[:, :3]
        faces = np.loadtxt(f, max_rows=nf, dtype=np.int64)
    assert (faces[:, 0] == 3).all(), "triangles only"
    return v, faces[:, 1:4].astype(np.uint32)


def main():
    src, dst = sys.argv[1], sys.argv[2]
    v, f = read_ply(src)
    n = np.zeros_like(v)
    tri = v[f]
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-20)
    lo, hi = v.min(axis=0), v.max(axis=0)
    centre = (lo + hi) / 2
    radius = float(np.linalg.norm(hi - lo)) / 2
    blobs = [v.tobytes(), n.astype(np.float32).tobytes(), f.tobytes()]
    views, offset = [], 0
    for b in blobs:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(b)})
        offset += len(b)
    doc = {
        "asset": {"version": "2.0", "generator": "caustic scripts/make-dragon-glb.py"},
        "buffers": [{"byteLength": offset}],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(v), "type": "VEC3",
             "min": lo.tolist(), "max": hi.tolist()},
            {"bufferView": 1, "componentType": 5126, "count": len(v), "type": "VEC3"},
            {"bufferView": 2, "componentType": 5125, "count": f.size, "type": "SCALAR"},
        ],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1],
                                                "metallicFactor": 0, "roughnessFactor": 0.5}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6, "aspectRatio": 16 / 9, "znear": 0.01}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 2000}]}},
        "nodes": [
            {"mesh": 0},
            {"camera": 0, "translation": [float(centre[0]), float(centre[1]), float(centre[2] + 3.2 * radius)]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "rotation": [-0.3826834, 0.0, 0.0, 0.9238795]},
        ],
        "scenes": [{"nodes": [0, 1, 2]}],
    }
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    data = b"".join(blobs)
    data += b"\0" * (-len(data) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(data), 0x004E4942) + data
    with open(dst, "wb") as out:
        out.write(b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body)
    print(f"{dst}: {len(v)} vertices, {len(f)} triangles, {12 + len(body)} bytes")


if __name__ == "__main__":
    main()
