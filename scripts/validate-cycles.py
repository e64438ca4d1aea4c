#!/usr/bin/env python3
"""Renders the same glTF file with caustic's path integrator and with
Blender's glTF importer followed by Cycles, and prints, per file, the ratio
of the means of each channel, the ratios over a 4×4 grid of blocks, and
relMSE (epsilon 1e-2).

Usage:
  python3.13 -m pip install bpy          # once: Blender as a module (Python 3.13 only)
  python3 -m pip install mitsuba numpy   # reads caustic's multi-channel EXR
  scripts/validate-cycles.py FILE.gltf|FILE.glb [...] [--blender PYTHON]
      [--width 256] [--height 256] [--spp-caustic 256] [--spp-cycles 256] [--max-depth 64]
      [--out DIR] [--sun LUX] [--build-scene] [--quads] [--match-model]

Both renderers read one file. A file without a camera gets one written into
a copy of it first (framing the bounding box Blender computes, 40° vertical
field of view, looking down −z from slightly above), so that both see the
same view. A file without punctual lights is lit by the uniform environment
caustic uses by default (radiance 1); Blender's world is set to the same
(black otherwise). `--sun LUX`
adds a `KHR_lights_punctual` directional light of that illuminance instead
(from above and in front), which both convert at 683 lm/W, and a black world.

`--build-scene` first builds a test scene in Blender and exports it as glTF
(a textured metallic-roughness sphere, a transmissive sphere, an emissive
panel and a point light on a floor), then validates that file too.
`--quads` also validates six single-material quads (grey, white and black
dielectrics of roughness 0.5 and 1, metals of roughness 0.5 and 1) under a
point light, which isolate the specular lobes, their multiple-scattering
compensation and the layering of the base. `--match-model` sets Blender's
Principled BSDFs to single-scattering `GGX` instead of Blender's default
`Multiscatter GGX`, to tell the compensation apart from the rest.

Cycles runs with its defaults for a physically based comparison: CPU, no
denoising, no adaptive sampling, no clamping, no glossy blur, reflective and
refractive caustics on, every bounce limit at --max-depth (caustic's glTF
scenes have no cap: Russian roulette ends paths), a box pixel
filter of one pixel, the Standard view transform (linear EXR output).
"""

import argparse
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


# ---------------------------------------------------------------- Blender side

def blender_job(job):
    """Runs inside Blender's Python: renders, or builds, or measures bounds."""
    import bpy
    import numpy as np

    def import_gltf(path):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        bpy.ops.import_scene.gltf(filepath=path)

    def world_bounds():
        lo = [math.inf] * 3
        hi = [-math.inf] * 3
        for obj in bpy.context.scene.objects:
            if obj.type != "MESH":
                continue
            for corner in obj.bound_box:
                p = obj.matrix_world @ __import__("mathutils").Vector(corner)
                for i in range(3):
                    lo[i] = min(lo[i], p[i])
                    hi[i] = max(hi[i], p[i])
        return lo, hi

    def exr_to_npy(exr, npy):
        img = bpy.data.images.load(exr)
        w, h = img.size
        px = np.array(img.pixels[:], dtype=np.float32).reshape(h, w, img.channels)
        np.save(npy, px[::-1, :, :3])

    kind = job["kind"]
    if kind == "bounds":
        import_gltf(job["gltf"])
        lo, hi = world_bounds()
        # Blender is z-up; glTF is y-up: (x, y, z)_gltf = (x, z, −y)_blender.
        lo_g = [lo[0], lo[2], -hi[1]]
        hi_g = [hi[0], hi[2], -lo[1]]
        with open(job["result"], "w") as f:
            json.dump({"min": lo_g, "max": hi_g}, f)
    elif kind == "render":
        import_gltf(job["gltf"])
        scene = bpy.context.scene
        cams = [o for o in scene.objects if o.type == "CAMERA"]
        if not cams:
            raise SystemExit("the file has no camera")
        scene.camera = sorted(cams, key=lambda o: o.name)[0]
        if job.get("match_model"):
            # Single-scattering GGX in every Principled BSDF: isolates
            # the multiple-scattering compensation of Blender's default.
            for mat in bpy.data.materials:
                if mat.use_nodes:
                    for node in mat.node_tree.nodes:
                        if node.type == "BSDF_PRINCIPLED":
                            node.distribution = "GGX"
        scene.render.engine = "CYCLES"
        c = scene.cycles
        c.device = "CPU"
        c.samples = job["spp"]
        c.use_adaptive_sampling = False
        c.use_denoising = False
        c.seed = job["seed"]
        c.sample_clamp_direct = 0.0
        c.sample_clamp_indirect = 0.0
        c.blur_glossy = 0.0
        c.caustics_reflective = True
        c.caustics_refractive = True
        n = job["max_depth"]
        c.max_bounces = n
        c.diffuse_bounces = n
        c.glossy_bounces = n
        c.transmission_bounces = n
        c.volume_bounces = n
        c.transparent_max_bounces = n
        c.pixel_filter_type = "BOX"
        c.filter_width = 1.0
        scene.render.resolution_x = job["width"]
        scene.render.resolution_y = job["height"]
        scene.render.resolution_percentage = 100
        scene.render.film_transparent = False
        scene.view_settings.view_transform = "Standard"
        scene.view_settings.look = "None"
        scene.view_settings.exposure = 0.0
        scene.view_settings.gamma = 1.0
        world = bpy.data.worlds.new("validation")
        world.use_nodes = True
        bg = world.node_tree.nodes["Background"]
        bg.inputs[0].default_value = (*job["world"], 1.0)
        bg.inputs[1].default_value = 1.0
        scene.world = world
        scene.render.image_settings.file_format = "OPEN_EXR"
        scene.render.image_settings.color_depth = "32"
        scene.render.filepath = job["exr"]
        start = time.time()
        bpy.ops.render.render(write_still=True)
        with open(job["result"], "w") as f:
            json.dump({"seconds": time.time() - start}, f)
        exr_to_npy(job["exr"], job["npy"])
    elif kind == "npy":
        exr_to_npy(job["exr"], job["npy"])
    elif kind == "build":
        build_test_scene(job["gltf"])
    else:
        raise SystemExit(f"unknown job {kind}")


def build_test_scene(path):
    """A floor, a textured metallic-roughness sphere, a transmissive sphere,
    an emissive panel and a point light, exported as glTF."""
    import bpy
    import numpy as np

    bpy.ops.wm.read_factory_settings(use_empty=True)

    def principled(name, **inputs):
        m = bpy.data.materials.new(name)
        m.use_nodes = True
        node = m.node_tree.nodes["Principled BSDF"]
        for k, v in inputs.items():
            node.inputs[k].default_value = v
        return m, node

    # A checker image for the textured sphere's base colour.
    size = 64
    img = bpy.data.images.new("checker", size, size)
    px = np.zeros((size, size, 4), dtype=np.float32)
    for y in range(size):
        for x in range(size):
            on = ((x // 8) + (y // 8)) % 2 == 0
            px[y, x] = (0.8, 0.3, 0.1, 1.0) if on else (0.1, 0.4, 0.8, 1.0)
    img.pixels[:] = px.ravel()
    img.filepath_raw = os.path.join(os.path.dirname(path), "checker.png")
    img.file_format = "PNG"
    img.save()

    bpy.ops.mesh.primitive_plane_add(size=8.0, location=(0, 0, 0))
    floor = bpy.context.object
    m, _ = principled("floor", **{"Base Color": (0.6, 0.6, 0.6, 1.0), "Roughness": 0.8, "Metallic": 0.0})
    floor.data.materials.append(m)

    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.7, location=(-1.0, 0.0, 0.7), segments=64, ring_count=32)
    bpy.ops.object.shade_smooth()
    textured = bpy.context.object
    m, node = principled("textured", **{"Roughness": 0.35, "Metallic": 0.3})
    tex = m.node_tree.nodes.new("ShaderNodeTexImage")
    tex.image = img
    m.node_tree.links.new(tex.outputs["Color"], node.inputs["Base Color"])
    textured.data.materials.append(m)

    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.6, location=(0.9, 0.6, 0.6), segments=64, ring_count=32)
    bpy.ops.object.shade_smooth()
    glass = bpy.context.object
    m, _ = principled(
        "glass",
        **{"Base Color": (0.9, 0.95, 1.0, 1.0), "Roughness": 0.1, "Metallic": 0.0, "Transmission Weight": 1.0, "IOR": 1.5},
    )
    glass.data.materials.append(m)

    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0.3, -1.6, 1.2), rotation=(math.radians(90), 0, 0))
    panel = bpy.context.object
    m, _ = principled(
        "panel",
        **{"Base Color": (0.0, 0.0, 0.0, 1.0), "Emission Color": (1.0, 0.7, 0.4, 1.0), "Emission Strength": 4.0},
    )
    panel.data.materials.append(m)

    light = bpy.data.lights.new("lamp", type="POINT")
    light.energy = 300.0  # W
    light.shadow_soft_size = 0.0
    obj = bpy.data.objects.new("lamp", light)
    obj.location = (0.5, 1.5, 3.5)
    bpy.context.scene.collection.objects.link(obj)

    bpy.ops.export_scene.gltf(filepath=path, export_format="GLTF_SEPARATE", export_lights=True, export_cameras=True)


# Single-material quads under a point light (`--quads`): one lobe at a time.
QUADS = [
    # name, base colour, metallic, roughness
    ("dielectric-0.5", (0.5, 0.5, 0.5), 0.0, 0.5),
    ("dielectric-1", (0.5, 0.5, 0.5), 0.0, 1.0),
    ("white-dielectric-1", (1.0, 1.0, 1.0), 0.0, 1.0),
    ("black-dielectric-1", (0.0, 0.0, 0.0), 0.0, 1.0),
    ("metal-0.5", (0.5, 0.5, 0.5), 1.0, 0.5),
    ("metal-1", (0.9, 0.9, 0.9), 1.0, 1.0),
]


def write_quad(path, base, metallic, roughness):
    """A 2 × 2 quad of one material, a camera looking down at it and a
    point light of 683 cd (1 W/sr after the 683 lm/W both renderers apply)."""
    import base64

    pos = [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)]
    idx = [0, 2, 1, 0, 3, 2]
    data = b"".join(struct.pack("<3f", *p) for p in pos)
    data += b"".join(struct.pack("<3f", 0, 1, 0) for _ in pos)
    data += struct.pack("<6H", *idx)
    cam = [0.0, 1.6, 2.4]
    n = math.sqrt(sum(c * c for c in cam))
    doc = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0},
                  {"camera": 0, "translation": cam, "rotation": look_rotation([-c / n for c in cam])},
                  {"translation": [0.6, 1.6, 0.8], "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.9, "aspectRatio": 1.0, "znear": 0.01}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 683.0}]}},
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": list(base) + [1.0],
                                                "metallicFactor": metallic, "roughnessFactor": roughness}}],
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 96, "byteLength": 12}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [-1, 0, -1], "max": [1, 0, 1]},
                      {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
                      {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}],
    }
    with open(path, "w") as f:
        json.dump(doc, f)


# ------------------------------------------------------------------ main side

def run_blender(python, job):
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(job, f)
        name = f.name
    try:
        out = subprocess.run([python, os.path.abspath(__file__), "--blender-job", name],
                             capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit(f"Blender job {job['kind']} failed:\n{out.stdout[-3000:]}\n{out.stderr[-3000:]}")
    finally:
        os.unlink(name)


def read_gltf_json(path):
    """The JSON of a .gltf, or of a .glb's first chunk, and the .glb's binary chunk."""
    data = open(path, "rb").read()
    if data[:4] == b"glTF":
        length = struct.unpack_from("<I", data, 12)[0]
        doc = json.loads(data[20:20 + length])
        rest = data[20 + length:]
        binary = rest[8:8 + struct.unpack_from("<I", rest, 0)[0]] if len(rest) >= 8 else None
        return doc, binary
    return json.loads(data), None


def write_like(src, doc, binary, dst_dir):
    """Writes `doc` beside copies of `src`'s resources; returns the new path."""
    base = os.path.basename(src)
    if binary is not None:
        out = os.path.join(dst_dir, os.path.splitext(base)[0] + ".glb")
        js = json.dumps(doc).encode()
        js += b" " * (-len(js) % 4)
        binary += b"\0" * (-len(binary) % 4)
        total = 12 + 8 + len(js) + 8 + len(binary)
        with open(out, "wb") as f:
            f.write(struct.pack("<III", 0x46546C67, 2, total))
            f.write(struct.pack("<I4s", len(js), b"JSON") + js)
            f.write(struct.pack("<I4s", len(binary), b"BIN\0") + binary)
        return out
    src_dir = os.path.dirname(os.path.abspath(src))
    for entry in os.listdir(src_dir):
        full = os.path.join(src_dir, entry)
        if os.path.isfile(full) and entry != base:
            shutil.copy(full, dst_dir)
    out = os.path.join(dst_dir, base)
    with open(out, "w") as f:
        json.dump(doc, f)
    return out


def look_rotation(forward, up=(0.0, 1.0, 0.0)):
    """The quaternion (x, y, z, w) turning −z to `forward` with +y near `up`."""
    def norm(v):
        n = math.sqrt(sum(c * c for c in v))
        return [c / n for c in v]

    def cross(a, b):
        return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]

    back = norm([-c for c in forward])
    right = norm(cross(up, back))
    true_up = cross(back, right)
    m = [[right[0], true_up[0], back[0]], [right[1], true_up[1], back[1]], [right[2], true_up[2], back[2]]]
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0:
        s = 0.5 / math.sqrt(trace + 1.0)
        return [(m[2][1] - m[1][2]) * s, (m[0][2] - m[2][0]) * s, (m[1][0] - m[0][1]) * s, 0.25 / s]
    if m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = 2.0 * math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2])
        return [0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s]
    if m[1][1] > m[2][2]:
        s = 2.0 * math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2])
        return [(m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s]
    s = 2.0 * math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1])
    return [(m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s, (m[1][0] - m[0][1]) / s]


def prepared(path, args, work):
    """The file both renderers read: `path`, or a copy with a camera and a
    sun added where asked; and the world colour for Blender."""
    doc, binary = read_gltf_json(path)
    changed = False
    aspect = args.width / args.height
    if not doc.get("cameras"):
        result = os.path.join(work, "bounds.json")
        run_blender(args.blender, {"kind": "bounds", "gltf": os.path.abspath(path), "result": result})
        b = json.load(open(result))
        lo, hi = b["min"], b["max"]
        center = [(l + h) / 2 for l, h in zip(lo, hi)]
        radius = max(1e-3, 0.5 * math.sqrt(sum((h - l) ** 2 for l, h in zip(lo, hi))))
        yfov = math.radians(40.0)
        fov = min(yfov, 2 * math.atan(math.tan(yfov / 2) * aspect))
        distance = radius / math.sin(fov / 2) * 1.05
        d = [0.0, 0.35, 1.0]
        n = math.sqrt(sum(c * c for c in d))
        d = [c / n for c in d]
        position = [c + distance * k for c, k in zip(center, d)]
        doc["cameras"] = [{"type": "perspective",
                           "perspective": {"yfov": yfov, "aspectRatio": aspect,
                                           "znear": distance * 1e-3}}]
        doc.setdefault("nodes", []).append({"name": "validation camera", "camera": 0,
                                            "translation": position,
                                            "rotation": look_rotation([-k for k in d])})
        scene = doc.get("scene", 0)
        doc["scenes"][scene]["nodes"].append(len(doc["nodes"]) - 1)
        changed = True
    # caustic lights a model without punctual lights by a uniform
    # environment of radiance 1 (docs/gltf.md); Blender's world matches.
    has_lights = bool(doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights"))
    world = [0.0, 0.0, 0.0] if has_lights else [1.0, 1.0, 1.0]
    if args.sun is not None:
        ext = doc.setdefault("extensions", {}).setdefault("KHR_lights_punctual", {})
        ext.setdefault("lights", []).append({"type": "directional", "intensity": args.sun, "name": "validation sun"})
        doc.setdefault("extensionsUsed", [])
        if "KHR_lights_punctual" not in doc["extensionsUsed"]:
            doc["extensionsUsed"].append("KHR_lights_punctual")
        doc["nodes"].append({"name": "validation sun",
                             "extensions": {"KHR_lights_punctual": {"light": len(ext["lights"]) - 1}},
                             "rotation": look_rotation([0.3, -1.0, -0.5])})
        doc["scenes"][doc.get("scene", 0)]["nodes"].append(len(doc["nodes"]) - 1)
        world = [0.0, 0.0, 0.0]
        changed = True
    if changed:
        path = write_like(path, doc, binary, work)
    return path, world


def read_caustic_exr(path):
    """The R, G, B channels of caustic's EXR (which also holds its AOVs,
    read here with Mitsuba's EXR reader)."""
    import numpy as np
    try:
        import mitsuba as mi
    except ImportError:
        sys.exit("reading caustic's EXR needs mitsuba: python3 -m pip install mitsuba")
    mi.set_variant("scalar_rgb")
    b = mi.Bitmap(path)
    names = [b.struct_()[i].name for i in range(b.channel_count())]
    px = np.array(b, copy=False).reshape(b.height(), b.width(), b.channel_count())
    return np.stack([px[..., names.index(c)] for c in ("R", "G", "B")], axis=-1).astype(np.float64)


def compare(ours, theirs):
    import numpy as np
    eps = 1e-2
    rel = float(np.mean((ours - theirs) ** 2 / (theirs ** 2 + eps)))
    mean = [float(ours[..., c].mean() / max(theirs[..., c].mean(), 1e-12)) for c in range(3)]
    h, w = ours.shape[:2]
    blocks = []
    for by in range(4):
        row = []
        for bx in range(4):
            sl = (slice(by * h // 4, (by + 1) * h // 4), slice(bx * w // 4, (bx + 1) * w // 4))
            t = theirs[sl].mean()
            row.append(float(ours[sl].mean() / t) if t > 1e-6 else float("nan"))
        blocks.append(row)
    return rel, mean, blocks


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--blender-job":
        blender_job(json.load(open(sys.argv[2])))
        return
    import numpy as np

    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("files", nargs="*")
    p.add_argument("--blender", default=os.path.expanduser("~/.pyenv/versions/3.13.0/bin/python"),
                   help="a Python that can import bpy")
    p.add_argument("--caustic", default=os.path.join(ROOT, "target", "release", "caustic"))
    p.add_argument("--width", type=int, default=256)
    p.add_argument("--height", type=int, default=256)
    p.add_argument("--spp-caustic", type=int, default=256)
    p.add_argument("--spp-cycles", type=int, default=256)
    p.add_argument("--max-depth", type=int, default=64,
                   help="Cycles' bounce limits (caustic's path integrator ends paths by Russian roulette)")
    p.add_argument("--sun", type=float, default=None, help="add a directional light of this many lux")
    p.add_argument("--build-scene", action="store_true")
    p.add_argument("--quads", action="store_true",
                   help="also validate single-material quads under a point light")
    p.add_argument("--match-model", action="store_true",
                   help="set Blender's Principled BSDFs to single-scattering GGX (not Blender's default)")
    p.add_argument("--out", default="cycles-validation")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    files = list(args.files)
    if args.build_scene:
        built = os.path.abspath(os.path.join(args.out, "built", "scene.gltf"))
        os.makedirs(os.path.dirname(built), exist_ok=True)
        run_blender(args.blender, {"kind": "build", "gltf": built})
        files.append(built)
    if args.quads:
        os.makedirs(os.path.join(args.out, "quads"), exist_ok=True)
        for name, base, metallic, roughness in QUADS:
            quad = os.path.abspath(os.path.join(args.out, "quads", name + ".gltf"))
            write_quad(quad, base, metallic, roughness)
            files.append(quad)
    if not files:
        p.error("no glTF file given")
    print("| file | mean ratio R G B | block ratios (min – max) | relMSE | caustic s | Cycles s |")
    print("| --- | --- | --- | --- | --- | --- |")
    for i, path in enumerate(files):
        work = os.path.abspath(os.path.join(args.out, f"{i}-{os.path.splitext(os.path.basename(path))[0]}"))
        os.makedirs(work, exist_ok=True)
        file, world = prepared(path, args, work)
        result = os.path.join(work, "cycles.json")
        run_blender(args.blender, {
            "kind": "render", "gltf": os.path.abspath(file), "exr": os.path.join(work, "cycles.exr"),
            "npy": os.path.join(work, "cycles.npy"), "result": result, "spp": args.spp_cycles,
            "seed": 1, "max_depth": args.max_depth, "width": args.width, "height": args.height,
            "world": world, "match_model": args.match_model})
        cycles_seconds = json.load(open(result))["seconds"]
        exr = os.path.join(work, "caustic.exr")
        cmd = [args.caustic, "render", file, "--exr", exr, "--integrator", "path",
               "--spp", str(args.spp_caustic), "--width", str(args.width), "--height", str(args.height)]
        start = time.time()
        out = subprocess.run(cmd, capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit(f"caustic failed: {' '.join(cmd)}\n{out.stderr}")
        caustic_seconds = time.time() - start
        ours = read_caustic_exr(exr)
        theirs = np.load(os.path.join(work, "cycles.npy")).astype(np.float64)
        rel, mean, blocks = compare(ours, theirs)
        flat = [b for row in blocks for b in row if not math.isnan(b)]
        print(f"| `{os.path.basename(path)}` | {mean[0]:.3f} {mean[1]:.3f} {mean[2]:.3f} | "
              f"{min(flat):.3f} – {max(flat):.3f} | {rel:.4f} | {caustic_seconds:.1f} | {cycles_seconds:.1f} |")
        with open(os.path.join(work, "blocks.json"), "w") as f:
            json.dump({"mean": mean, "blocks": blocks, "relmse": rel}, f, indent=1)


if __name__ == "__main__":
    main()
