#!/usr/bin/env python3
"""Path-traced samples per second of caustic against Mitsuba 3 `llvm_ad_rgb`,
both at the same thread count, on two scenes set up identically in both:

* glass: Mitsuba's Cornell box without its blocks, a mirror sphere and a
  glass sphere (IOR 1.5), the light black (as caustic's area lights), box
  filter, unbounded depth, 256 × 256 (the "specular" scene of
  validate-mitsuba.py);
* dragon: the diffuse Stanford dragon on a floor before a backdrop under one
  area light, 640 × 360, depth 64.

Each round renders every (scene, spp) with caustic (`--integrator path`,
Embree) and then with Mitsuba, interleaved; the best of --rounds is kept.
Times are render only: caustic's "wall time" (after loading and the
accelerator build), Mitsuba's `mi.render` until the image is computed, after
a warm-up render at the same pass layout that compiles its kernel. Mitsuba
renders more than 64 spp in passes of 64.

relMSE (ε = 1e-2) is against a long Mitsuba render per scene (--ref-spp),
made once and kept in --cache. Several --caustic binaries (comma-separated)
are each timed in every round, to compare builds in one run. The mean ratio caustic / reference shows
that both renderers converge to the same image.

usage: scripts/peer-bench.py [--spp 4,16,64,256] [--rounds 3] [--threads 2]
                             [--scenes glass,dragon] [--caustic BINARY[,BINARY...]]
                             [--cache ~/.cache/caustic/peer-bench] [--ref-spp 1024]
                             [--dragon-ply PATH]

Needs `mitsuba==3.9.1` and numpy; the LLVM variant needs libLLVM >= 18
(Debian: libllvm19; DRJIT_LIBLLVM_PATH is set to it when unset).
"""

import argparse
import glob
import gzip
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EPSILON = 1e-2

if "DRJIT_LIBLLVM_PATH" not in os.environ:
    libs = glob.glob("/usr/lib/x86_64-linux-gnu/libLLVM-*.so") + glob.glob("/usr/lib/llvm-*/lib/libLLVM-*.so")
    libs = [p for p in libs if re.search(r"libLLVM-(\d+)", p)]
    libs.sort(key=lambda p: int(re.search(r"libLLVM-(\d+)", p).group(1)))
    if libs and int(re.search(r"libLLVM-(\d+)", libs[-1]).group(1)) >= 18:
        os.environ["DRJIT_LIBLLVM_PATH"] = libs[-1]

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")
T = mi.ScalarTransform4f


def rgb(v):
    return {"type": "rgb", "value": v}


# ------------------------------------------------------------------ scenes ---

GLASS_TOML = """[render]
width = 256
height = 256
spp = 16
seed = 1
integrator = "path"
tone_map = "clamp"

[camera]
position = [0, 0, 3.9]
look_at = [0, 0, 2.9]
up = [0, 1, 0]
vfov = 39.3077

[materials.white]
diffuse = [0.885809, 0.698859, 0.666422]
[materials.green]
diffuse = [0.105421, 0.37798, 0.076425]
[materials.red]
diffuse = [0.570068, 0.0430135, 0.0443706]
[materials.mirror]
ambient = [0, 0, 0]
diffuse = [0, 0, 0]
mirror = { reflectivity = 1.0 }
[materials.glass]
diffuse = [0, 0, 0]
dielectric = { ior = 1.5 }
"""


def glass_scenes(spp_per_pass):
    """(caustic TOML, Mitsuba dictionary) of the glass Cornell box."""
    d = mi.cornell_box()
    del d["small-box"], d["large-box"]
    d["sensor"]["film"]["width"] = 256
    d["sensor"]["film"]["height"] = 256
    d["sensor"]["film"]["rfilter"] = {"type": "box"}
    d["integrator"] = {"type": "path", "max_depth": -1}
    if spp_per_pass:
        d["integrator"]["samples_per_pass"] = spp_per_pass
    d["black"] = {"type": "diffuse", "reflectance": rgb([0.0, 0.0, 0.0])}
    d["light"]["bsdf"] = {"type": "ref", "id": "black"}
    d["mirror"] = {"type": "conductor", "material": "none"}
    d["glass"] = {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}
    d["mirror-sphere"] = {"type": "sphere", "center": [-0.45, -0.65, -0.3], "radius": 0.35,
                          "bsdf": {"type": "ref", "id": "mirror"}}
    d["glass-sphere"] = {"type": "sphere", "center": [0.45, -0.65, 0.25], "radius": 0.35,
                         "bsdf": {"type": "ref", "id": "glass"}}
    return caustic_glass_toml(d), d


def caustic_glass_toml(d):
    """caustic's scene for the dictionary: walls as quads, the light as an
    area light, the spheres (transforms read from Mitsuba's own matrices)."""
    def m(t):
        return np.array(t.matrix, dtype=np.float64).reshape(4, 4)

    def p(mat, v):
        return (mat @ np.array([*v, 1.0]))[:3]

    def v(mat, x):
        return (mat @ np.array([*x, 0.0]))[:3]

    def f(x):
        return "[" + ", ".join(f"{c:.9g}" for c in x) + "]"

    out = [GLASS_TOML]
    for key, value in d.items():
        if not isinstance(value, dict):
            continue
        if value.get("type") == "rectangle":
            mat = m(value["to_world"])
            corner, u, w = p(mat, [-1, -1, 0]), v(mat, [2, 0, 0]), v(mat, [0, 2, 0])
            if "emitter" in value:
                out += ["[[lights]]", 'type = "area"', f"position = {f(p(mat, [0, 0, 0]))}",
                        f"u = {f(u)}", f"v = {f(w)}",
                        f"colour = {f(value['emitter']['radiance']['value'])}", "intensity = 1.0", ""]
            else:
                out += ["[[objects]]", f'name = "{key}"', 'type = "quad"', f"corner = {f(corner)}",
                        f"u = {f(u)}", f"v = {f(w)}", f'material = "{value["bsdf"]["id"]}"', ""]
        elif value.get("type") == "sphere":
            out += ["[[objects]]", f'name = "{key}"', 'type = "sphere"', f"center = {f(value['center'])}",
                    f"radius = {value['radius']}", f'material = "{value["bsdf"]["id"]}"', ""]
    return "\n".join(out)


DRAGON_TOML = """[render]
width = 640
height = 360
spp = 16
seed = 1
max_depth = 64
integrator = "path"
[camera]
position = [0.0, 1.35, 4.3]
look_at = [0.0, 0.62, 0.0]
up = [0.0, 1.0, 0.0]
vfov = 33
[materials.dragon]
diffuse = [0.7, 0.7, 0.7]
[materials.floor]
diffuse = [0.62, 0.60, 0.56]
[materials.backdrop]
diffuse = [0.35, 0.42, 0.55]
[[lights]]
type = "area"
position = [0.6, 4.0, 1.2]
u = [1.6, 0.0, 0.0]
v = [0.0, 0.0, 1.6]
colour = [1.0, 0.95, 0.88]
intensity = 24.0
[[objects]]
name = "floor"
type = "quad"
center = [0.0, 0.0, -1.0]
size = [14.0, 10.0]
normal = [0.0, 1.0, 0.0]
material = "floor"
[[objects]]
name = "backdrop"
type = "quad"
center = [0.0, 3.0, -3.0]
size = [14.0, 6.0]
normal = [0.0, 0.0, 1.0]
material = "backdrop"
[[objects]]
name = "dragon"
type = "mesh"
file = "DRAGON_PLY"
scale = 10.0
translate = [0.06, -0.528, 0.045]
smooth = true
material = "dragon"
"""


def dragon_scenes(ply, spp_per_pass):
    """(caustic TOML, Mitsuba dictionary) of the dragon scene (max_depth 65
    in Mitsuba counts the emitter vertex: 64 bounces as caustic's)."""
    integrator = {"type": "path", "max_depth": 65}
    if spp_per_pass:
        integrator["samples_per_pass"] = spp_per_pass
    d = {"type": "scene",
         "integrator": integrator,
         "sensor": {"type": "perspective", "fov": 33, "fov_axis": "y",
                    "to_world": T().look_at(origin=[0, 1.35, 4.3], target=[0, 0.62, 0], up=[0, 1, 0]),
                    "film": {"type": "hdrfilm", "width": 640, "height": 360, "rfilter": {"type": "box"},
                             "pixel_format": "rgb"},
                    "sampler": {"type": "independent", "sample_count": 16}},
         "floor": {"type": "rectangle", "to_world": T().translate([0, 0, -1]).rotate([1, 0, 0], -90).scale([7, 5, 1]),
                   "bsdf": {"type": "diffuse", "reflectance": rgb([0.62, 0.60, 0.56])}},
         "backdrop": {"type": "rectangle", "to_world": T().translate([0, 3, -3]).scale([7, 3, 1]),
                      "bsdf": {"type": "diffuse", "reflectance": rgb([0.35, 0.42, 0.55])}},
         "light": {"type": "rectangle",
                   "to_world": T().translate([0.6, 4, 1.2]).rotate([1, 0, 0], 90).scale([0.8, 0.8, 1]),
                   "bsdf": {"type": "diffuse", "reflectance": rgb([0, 0, 0])},
                   "emitter": {"type": "area", "radiance": rgb([24.0, 22.8, 21.12])}},
         "dragon": {"type": "ply", "filename": ply,
                    "to_world": T().translate([0.06, -0.528, 0.045]).scale(10.0),
                    "bsdf": {"type": "diffuse", "reflectance": rgb([0.7, 0.7, 0.7])}}}
    return DRAGON_TOML.replace("DRAGON_PLY", ply), d


# --------------------------------------------------------------- rendering ---

def caustic_render(binary, toml_path, spp, seed, threads, exr):
    """(image, render seconds) of caustic's path integrator."""
    cmd = [binary, "render", toml_path, "--spp", str(spp), "--seed", str(seed), "--threads", str(threads),
           "--integrator", "path", "--exr", exr, "--quiet"]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    seconds = float(re.search(r"wall time: ([0-9.]+) s", out).group(1))
    return np.array(mi.Bitmap(exr), dtype=np.float64)[:, :, :3], seconds


class MitsubaScene:
    """A loaded Mitsuba scene per pass layout (single pass up to 64 spp)."""

    def __init__(self, make):
        self.make = make
        self.scenes = {}

    def render(self, spp, seed):
        per_pass = 0 if spp <= 64 else 64
        if per_pass not in self.scenes:
            scene = mi.load_dict(self.make(per_pass))
            self.scenes[per_pass] = scene
            # Warm-up at the same pass layout: the kernel is compiled (or
            # read from Dr.Jit's cache) outside the timed render.
            img = mi.render(scene, spp=per_pass or spp, seed=10_000_019)
            dr.eval(img)
            dr.sync_thread()
        scene = self.scenes[per_pass]
        start = time.perf_counter()
        img = mi.render(scene, spp=spp, seed=seed)
        dr.eval(img)
        dr.sync_thread()
        seconds = time.perf_counter() - start
        return np.array(img, dtype=np.float64)[:, :, :3], seconds


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + EPSILON)))


def mean_ratio(x, ref):
    return float(x.mean() / ref.mean())


def cpu_description():
    """The processor's model and its widest vectors: Mitsuba's LLVM backend
    compiles its kernels for the host's, so the ratio depends on them."""
    model, flags = "unknown", set()
    try:
        for line in open("/proc/cpuinfo"):
            key, _, value = line.partition(":")
            if key.strip() == "model name":
                model = value.strip()
            elif key.strip() == "flags":
                flags = set(value.split())
    except OSError:
        pass
    width = "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "SSE"
    return f"{model}, {width}"


def load_uptime():
    with open("/proc/loadavg") as f:
        return f.read().split()[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", default="4,16,64,256")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--scenes", default="glass,dragon")
    ap.add_argument("--caustic", default=os.path.join(ROOT, "target", "release", "caustic"))
    ap.add_argument("--cache", default=os.path.expanduser("~/.cache/caustic/peer-bench"))
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--dragon-ply", default="")
    args = ap.parse_args()
    spps = [int(s) for s in args.spp.split(",")]
    binaries = args.caustic.split(",")
    os.makedirs(args.cache, exist_ok=True)
    dr.set_thread_count(args.threads)
    work = os.path.join(args.cache, "work")
    os.makedirs(work, exist_ok=True)

    scenes = {}
    for name in args.scenes.split(","):
        if name == "glass":
            toml, _ = glass_scenes(0)
            scenes[name] = (toml, lambda per_pass: glass_scenes(per_pass)[1])
        elif name == "dragon":
            ply = args.dragon_ply or os.path.join(args.cache, "dragon_vrip.ply")
            if not os.path.exists(ply):
                packed = os.path.join(ROOT, "assets", "dragon_vrip.ply.gz")
                for candidate in [packed, os.path.expanduser("~/.cache/caustic/assets/dragon_vrip.ply.gz")]:
                    if os.path.exists(candidate):
                        with gzip.open(candidate) as src, open(ply, "wb") as dst:
                            shutil.copyfileobj(src, dst)
                        break
                else:
                    sys.exit("the dragon's PLY was not found: give --dragon-ply")
            toml, _ = dragon_scenes(ply, 0)
            scenes[name] = (toml, lambda per_pass, ply=ply: dragon_scenes(ply, per_pass)[1])
        else:
            sys.exit(f"unknown scene {name}")

    print(f"caustic {', '.join(binaries)}; mitsuba {mi.__version__} llvm_ad_rgb; threads {args.threads}; "
          f"load {load_uptime()} at start; cpu {cpu_description()}")
    rows = []
    for name, (toml, make) in scenes.items():
        toml_path = os.path.join(work, f"{name}.toml")
        with open(toml_path, "w") as f:
            f.write(toml)
        mitsuba = MitsubaScene(make)
        ref_path = os.path.join(args.cache, f"{name}-reference-{args.ref_spp}.exr")
        if not os.path.exists(ref_path):
            print(f"{name}: rendering the reference ({args.ref_spp} spp, Mitsuba) once into {ref_path}")
            ref_scene = mi.load_dict(make(64))
            img = mi.render(ref_scene, spp=args.ref_spp, seed=777)
            mi.Bitmap(img).write(ref_path)
        ref = np.array(mi.Bitmap(ref_path), dtype=np.float64)[:, :, :3]
        pixels = ref.shape[0] * ref.shape[1]
        for spp in spps:
            best = {}
            for _ in range(args.rounds):
                for b, binary in enumerate(binaries):
                    img, s = caustic_render(binary, toml_path, spp, 1, args.threads,
                                            os.path.join(work, f"{name}-{spp}-{b}.exr"))
                    if b not in best or s < best[b][1]:
                        best[b] = (img, s)
                img, s = mitsuba.render(spp, 1)
                if "mitsuba" not in best or s < best["mitsuba"][1]:
                    best["mitsuba"] = (img, s)
            mi_img, ms = best["mitsuba"]
            for b, binary in enumerate(binaries):
                ci, cs = best[b]
                label = name if len(binaries) == 1 else f"{name} ({os.path.basename(binary)})"
                row = (label, spp, cs, ms, pixels * spp / cs, pixels * spp / ms, relmse(ci, ref),
                       relmse(mi_img, ref), mean_ratio(ci, ref), mean_ratio(mi_img, ref), load_uptime())
                rows.append(row)
                print(f"{label:6} {spp:4} spp  caustic {cs:7.3f} s {row[4] / 1e6:6.3f} MS/s  "
                      f"mitsuba {ms:7.3f} s {row[5] / 1e6:6.3f} MS/s  ratio {ms / cs:5.2f}x  "
                      f"relMSE {row[6]:.3e} / {row[7]:.3e}  mean/ref {row[8]:.4f} / {row[9]:.4f}  load {row[10]}",
                      flush=True)
    print()
    print("| scene | spp | caustic s | Mitsuba s | caustic Msamples/s | Mitsuba Msamples/s | "
          "caustic / Mitsuba speed | relMSE caustic | relMSE Mitsuba | mean / reference (caustic, Mitsuba) | load |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        print(f"| {r[0]} | {r[1]} | {r[2]:.3f} | {r[3]:.3f} | {r[4] / 1e6:.3f} | {r[5] / 1e6:.3f} | "
              f"{r[3] / r[2]:.2f}× | {r[6]:.2e} | {r[7]:.2e} | {r[8]:.4f}, {r[9]:.4f} | {r[10]} |")


if __name__ == "__main__":
    main()
