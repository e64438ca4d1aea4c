#!/usr/bin/env python3
"""Renders the same scenes with caustic's path integrator and with Mitsuba 3
(variant scalar_rgb, `path` integrator, box pixel filter) and prints, per
scene, relMSE (epsilon 1e-2) and the ratio of the mean of each channel.

Scenes: Mitsuba's Cornell box (diffuse); the same box with a mirror sphere
and a glass sphere instead of the blocks; the box with a rough gold sphere,
a rough glass sphere and a plastic sphere; the box without its ceiling light
lit by a spot light (spot), a directional light through its open front
(sun), or an emitting sphere and an emitting panel that also reflect
(emitters).

Usage:
  python3 -m pip install mitsuba numpy      # once (a virtual environment is fine)
  scripts/validate-mitsuba.py [--spp-caustic N] [--spp-mitsuba N] [--size 256]
                              [--out DIR] [--scenes cornell,specular,materials]
                              [--caustics path|map|path,map] [--photons N]
                              [--region X0,Y0,X1,Y1] [--halves]
                              [--equal-time SECONDS,...]

--caustics map renders caustic's images with photon-mapped caustics (L S+ D
from a photon map of --photons photons, the rest path traced) instead of
pure path tracing; Mitsuba stays a pure path tracer. A list (path,map) gives
one row per mode against the same Mitsuba image. --region adds the ratio of
the means over a pixel rectangle (x0 ≤ x < x1, y0 ≤ y < y1, y down, e.g.
around a caustic). --halves renders every image as two halves of its samples
with different seeds and averages them; the halves' differences then give
the standard error of each mean ratio and the relMSE that the two images'
noise alone would give (the rest is bias, e.g. the photon map's blur).

With --xml FILE[,FILE...], both renderers render each Mitsuba XML scene
file as it is (caustic reads Mitsuba's format): `-D NAME=VALUE` sets the
files' parameters for both (e.g. -D resx=128), the sample counts are
--spp-caustic and --spp-mitsuba, and --variant picks Mitsuba's variant
(scalar_rgb or llvm_ad_rgb). --reference-exr F1,F2,... (one per --xml file,
empty to skip) also compares caustic's image with an EXR rendered elsewhere,
such as the references Mitsuba's test scenes come with.

With --equal-time SPP,SPP,..., both renderers render the Cornell box at those
sample counts instead, and the script prints render time and relMSE against a
converged Mitsuba image, and the ratio of the errors at equal time (time
against error, both curves; --plot draws them).
"""

import argparse
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

try:
    import mitsuba as mi
except ImportError:
    sys.exit("mitsuba is not installed: python3 -m pip install mitsuba numpy")

mi.set_variant("scalar_rgb")
from mitsuba import ScalarTransform4f as T  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EPSILON = 1e-2


# ---------------------------------------------------------------- scenes ---

def matrix(transform):
    return np.array(transform.matrix, dtype=np.float64).reshape(4, 4)


def point(m, p):
    return (m @ np.array([*p, 1.0]))[:3]


def vector(m, v):
    return (m @ np.array([*v, 0.0]))[:3]


def fmt(v):
    return "[" + ", ".join(f"{x:.9g}" for x in v) + "]"


def cornell(size, boxes=True):
    """Mitsuba's Cornell box dictionary, with a box filter and no integrator
    settings of its own; `boxes=False` removes the two blocks."""
    d = mi.cornell_box()
    d["sensor"]["film"]["width"] = size
    d["sensor"]["film"]["height"] = size
    d["sensor"]["film"]["rfilter"] = {"type": "box"}
    d["integrator"] = {"type": "path", "max_depth": -1}
    # caustic's area lights are emitters only: black, opaque, reflecting
    # nothing. Mitsuba's box gives its light the white diffuse BSDF, which
    # would reflect the room's light back down (about 1 % of the image).
    d["black"] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    d["light"]["bsdf"] = {"type": "ref", "id": "black"}
    if not boxes:
        del d["small-box"]
        del d["large-box"]
    return d


def with_specular_spheres(d):
    d["mirror"] = {"type": "conductor", "material": "none"}
    d["glass"] = {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}
    d["mirror-sphere"] = {"type": "sphere", "center": [-0.45, -0.65, -0.3], "radius": 0.35,
                          "bsdf": {"type": "ref", "id": "mirror"}}
    d["glass-sphere"] = {"type": "sphere", "center": [0.45, -0.65, 0.25], "radius": 0.35,
                         "bsdf": {"type": "ref", "id": "glass"}}
    return d


GOLD_ETA = [0.143036, 0.375307, 1.44205]
GOLD_K = [3.983, 2.38556, 1.60336]


def with_material_spheres(d):
    d["rough-gold"] = {"type": "roughconductor", "distribution": "ggx", "alpha": 0.2,
                       "eta": {"type": "rgb", "value": GOLD_ETA}, "k": {"type": "rgb", "value": GOLD_K}}
    d["rough-glass"] = {"type": "roughdielectric", "distribution": "ggx", "alpha": 0.15,
                        "int_ior": 1.5, "ext_ior": 1.0}
    d["plastic"] = {"type": "plastic", "int_ior": 1.5, "ext_ior": 1.0, "nonlinear": False,
                    "diffuse_reflectance": {"type": "rgb", "value": [0.1, 0.27, 0.36]}}
    for name, bsdf, center in [("gold-sphere", "rough-gold", [-0.55, -0.7, -0.25]),
                               ("glass-sphere", "rough-glass", [0.0, -0.7, 0.3]),
                               ("plastic-sphere", "plastic", [0.55, -0.7, -0.25])]:
        d[name] = {"type": "sphere", "center": center, "radius": 0.3, "bsdf": {"type": "ref", "id": bsdf}}
    return d


def with_lights(d, kind):
    """The box without its ceiling light, lit by a spot light, a
    directional light through the open front, or two emitting shapes that
    also reflect (a sphere and a rectangle with white diffuse BSDFs)."""
    del d["light"]
    if kind == "spot":
        d["spot"] = {"type": "spot", "intensity": {"type": "rgb", "value": [6.0, 5.0, 4.0]},
                     "cutoff_angle": 35.0, "beam_width": 20.0,
                     "to_world": T().look_at(origin=[0.2, 0.95, 0.1], target=[-0.2, -1.0, -0.1], up=[0, 0, 1])}
    elif kind == "sun":
        d["sun"] = {"type": "directional", "direction": [-0.25, -0.35, -1.0],
                    "irradiance": {"type": "rgb", "value": [3.0, 2.8, 2.5]}}
    else:
        d["lamp-sphere"] = {"type": "sphere", "center": [0.35, -0.55, 0.1], "radius": 0.25,
                            "bsdf": {"type": "ref", "id": "white"},
                            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [4.0, 3.0, 2.0]}}}
        d["lamp-panel"] = {"type": "rectangle", "bsdf": {"type": "ref", "id": "white"},
                           "to_world": T().translate([-0.5, 0.3, -0.99]).scale(0.25),
                           "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [2.0, 3.0, 5.0]}}}
    return d


def emitting_material(name, bsdf, emitter):
    """`bsdf` with the emission of area emitter `emitter`, as material `name`."""
    return caustic_material(name, bsdf) + f"\nemission = {fmt(emitter['radiance']['value'])}"


def caustic_material(name, bsdf):
    t = bsdf["type"]
    lines = [f"[materials.{name}]"]
    if t == "diffuse":
        lines.append(f"diffuse = {fmt(bsdf['reflectance']['value'])}")
    elif t == "conductor" and bsdf.get("material") == "none":
        lines += ["ambient = [0, 0, 0]", "diffuse = [0, 0, 0]", "mirror = { reflectivity = 1.0 }"]
    elif t == "dielectric":
        lines += ["diffuse = [0, 0, 0]", f"dielectric = {{ ior = {bsdf['int_ior']} }}"]
    elif t == "roughconductor":
        lines += ["diffuse = [0, 0, 0]",
                  f"conductor = {{ eta = {fmt(bsdf['eta']['value'])}, k = {fmt(bsdf['k']['value'])}, "
                  f"roughness = {bsdf['alpha']} }}"]
    elif t == "roughdielectric":
        lines += ["diffuse = [0, 0, 0]", f"dielectric = {{ ior = {bsdf['int_ior']}, roughness = {bsdf['alpha']} }}"]
    elif t == "plastic":
        lines += [f"diffuse = {fmt(bsdf['diffuse_reflectance']['value'])}",
                  f"coating = {{ ior = {bsdf['int_ior']} }}"]
    else:
        raise ValueError(f"no caustic equivalent for {t}")
    return "\n".join(lines)


def caustic_scene(d, spp, seed=1):
    """The caustic scene file equivalent to Mitsuba dictionary `d`."""
    sensor = d["sensor"]
    film = sensor["film"]
    if film["width"] != film["height"]:
        raise ValueError("square films only (fov_axis 'smaller' is then the vertical fov)")
    m = matrix(sensor["to_world"])
    origin = point(m, [0, 0, 0])
    out = [
        "[render]",
        f"width = {film['width']}",
        f"height = {film['height']}",
        f"spp = {spp}",
        f"seed = {seed}",
        'integrator = "path"',
        'tone_map = "clamp"',
        "",
        "[camera]",
        f"position = {fmt(origin)}",
        f"look_at = {fmt(origin + vector(m, [0, 0, 1]))}",
        f"up = {fmt(vector(m, [0, 1, 0]))}",
        f"vfov = {sensor['fov']}",
        "",
    ]
    for key, value in d.items():
        if isinstance(value, dict) and value.get("type") in (
                "diffuse", "conductor", "dielectric", "roughconductor", "roughdielectric", "plastic"):
            out += [caustic_material(key, value), ""]
    def material_of(key, value):
        """The material of shape `key`: its BSDF's, or a copy that emits."""
        if "emitter" not in value:
            return value["bsdf"]["id"]
        out.extend([emitting_material(f"{key}-emitting", d[value["bsdf"]["id"]], value["emitter"]), ""])
        return f"{key}-emitting"

    for key, value in d.items():
        if not isinstance(value, dict):
            continue
        t = value.get("type")
        if t == "spot":
            m = matrix(value["to_world"])
            out += ["[[lights]]", 'type = "spot"', f"position = {fmt(point(m, [0, 0, 0]))}",
                    f"direction = {fmt(vector(m, [0, 0, 1]))}", f"cutoff_angle = {value['cutoff_angle']}",
                    f"beam_width = {value['beam_width']}", f"colour = {fmt(value['intensity']['value'])}", ""]
        elif t == "directional":
            out += ["[[lights]]", 'type = "directional"', f"direction = {fmt(value['direction'])}",
                    f"colour = {fmt(value['irradiance']['value'])}", ""]
        elif t == "rectangle":
            m = matrix(value["to_world"])
            corner, u, v = point(m, [-1, -1, 0]), vector(m, [2, 0, 0]), vector(m, [0, 2, 0])
            if "emitter" in value and value["bsdf"]["id"] == "black":
                out += ["[[lights]]", 'type = "area"', f"position = {fmt(point(m, [0, 0, 0]))}",
                        f"u = {fmt(u)}", f"v = {fmt(v)}",
                        f"colour = {fmt(value['emitter']['radiance']['value'])}", "intensity = 1.0", ""]
                continue
            material = material_of(key, value)
            out += ["[[objects]]", f'name = "{key}"', 'type = "quad"', f"corner = {fmt(corner)}",
                    f"u = {fmt(u)}", f"v = {fmt(v)}", f'material = "{material}"', ""]
        elif t == "cube":
            m = matrix(value["to_world"])
            # The six faces of [-1, 1]^3, each facing outward (u × v).
            faces = [([-1, -1, 1], [2, 0, 0], [0, 2, 0]), ([-1, 1, -1], [2, 0, 0], [0, -2, 0]),
                     ([1, -1, -1], [0, 2, 0], [0, 0, 2]), ([-1, -1, 1], [0, 2, 0], [0, 0, -2]),
                     ([-1, 1, -1], [0, 0, 2], [2, 0, 0]), ([-1, -1, -1], [2, 0, 0], [0, 0, 2])]
            for i, (c, a, b) in enumerate(faces):
                out += ["[[objects]]", f'name = "{key} {i}"', 'type = "quad"', f"corner = {fmt(point(m, c))}",
                        f"u = {fmt(vector(m, a))}", f"v = {fmt(vector(m, b))}",
                        f'material = "{value["bsdf"]["id"]}"', ""]
        elif t == "sphere":
            material = material_of(key, value)
            out += ["[[objects]]", f'name = "{key}"', 'type = "sphere"', f"center = {fmt(value['center'])}",
                    f"radius = {value['radius']}", f'material = "{material}"', ""]
    return "\n".join(out)


SCENES = {
    "cornell": lambda size: cornell(size),
    "specular": lambda size: with_specular_spheres(cornell(size, boxes=False)),
    "materials": lambda size: with_material_spheres(cornell(size, boxes=False)),
    "spot": lambda size: with_lights(cornell(size), "spot"),
    "sun": lambda size: with_lights(cornell(size), "sun"),
    "emitters": lambda size: with_lights(cornell(size), "emitters"),
}


# ------------------------------------------------------------- rendering ---

def caustic_binary(given):
    if given:
        return given
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    return os.path.join(ROOT, "target", "release", "caustic")


def render_caustic(binary, toml_text, out_dir, name, spp=None, seconds=None, seed=1, caustics="path",
                   photons=None):
    scene = os.path.join(out_dir, f"{name}.toml")
    with open(scene, "w") as f:
        f.write(toml_text)
    exr = os.path.join(out_dir, f"{name}-caustic.exr")
    cmd = [binary, "render", scene, "--exr", exr, "--quiet", "--seed", str(seed), "--caustics", caustics]
    if caustics == "map" and photons is not None:
        cmd += ["--photons", str(photons)]
    if spp is not None:
        cmd += ["--spp", str(spp)]
    start = time.time()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    wall = time.time() - start
    return np.array(mi.Bitmap(exr), dtype=np.float64)[:, :, :3], wall


def render_mitsuba(d, spp, seed=0):
    scene = mi.load_dict(d)
    start = time.time()
    img = mi.render(scene, spp=spp, seed=seed)
    wall = time.time() - start
    return np.array(img, dtype=np.float64)[:, :, :3], wall


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + EPSILON)))


def mean_ratio(x, ref):
    return [float(x[:, :, c].mean() / ref[:, :, c].mean()) for c in range(3)]


def halves_render(render, spp, seeds, halves):
    """`render(spp, seed)` once, or (with `halves`) as two renders of half
    the samples with seeds `seeds[0]`, `seeds[1]`: (image, seconds, the two
    halves or None)."""
    if not halves:
        img, wall = render(spp, seeds[0])
        return img, wall, None
    a, ta = render(spp // 2, seeds[0])
    b, tb = render(spp - spp // 2, seeds[1])
    return 0.5 * (a + b), ta + tb, (a, b)


def mean_ratio_error(ours, theirs, window):
    """Standard error of each channel's mean ratio over `window` (numpy
    index), from the two halves of each image: the variance of a pixel of
    the averaged image is (a − b)² / 4, pixels taken as independent."""
    out = []
    for c in range(3):
        rel2 = 0.0
        for a, b in (ours, theirs):
            m = 0.5 * (a[window][..., c] + b[window][..., c])
            var_mean = float(np.sum((a[window][..., c] - b[window][..., c]) ** 2) / 4.0) / m.size ** 2
            rel2 += var_mean / float(m.mean()) ** 2
        out.append(math.sqrt(rel2))
    return out


def noise_relmse(ours, theirs, ref):
    """The relMSE that the two images' noise alone gives (its expectation,
    estimated from the halves of each image): mean((σ²_x + σ²_ref) / (ref² + ε))."""
    var = sum((a - b) ** 2 / 4.0 for a, b in (ours, theirs))
    return float(np.mean(var / (ref ** 2 + EPSILON)))


def agreement_columns(row, r, theirs, ours_h, theirs_h, halves):
    """The noise relMSE and mean ratios (± standard errors with `halves`),
    added to `row` and returned as the line's last columns."""
    if not halves:
        return f"  {r[0]:.4f} {r[1]:.4f} {r[2]:.4f}"
    whole = (slice(None), slice(None))
    row["noise_relmse"] = noise_relmse(ours_h, theirs_h, theirs)
    row["mean_ratio_error"] = mean_ratio_error(ours_h, theirs_h, whole)
    return f" {row['noise_relmse']:>10.3e}  " + " ".join(
        f"{v:.4f}±{s:.4f}" for v, s in zip(r, row["mean_ratio_error"]))


def save_exr(path, img):
    mi.Bitmap(img.astype(np.float32)).write(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp-caustic", type=int, default=8192)
    ap.add_argument("--spp-mitsuba", type=int, default=4096)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--out", default="validation")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--equal-time", default="",
                    help="comma-separated sample counts: time against error on the Cornell box")
    ap.add_argument("--reference", help="converged Mitsuba EXR of the Cornell box for --equal-time")
    ap.add_argument("--plot", help="PNG plot of the --equal-time curves (needs matplotlib)")
    ap.add_argument("--caustics", default="path",
                    help="caustic's caustics: path (pure path tracing), map (photon map), or a list: path,map")
    ap.add_argument("--photons", type=int, default=2000000, help="photons emitted with --caustics map")
    ap.add_argument("--region", help="x0,y0,x1,y1: also the ratio of the means over these pixels (y down)")
    ap.add_argument("--halves", action="store_true",
                    help="two half renders per image: standard errors of the mean ratios and the noise's relMSE")
    ap.add_argument("--json", help="also write the results as JSON")
    ap.add_argument("--binary", help="the caustic binary to run (default: built with cargo)")
    ap.add_argument("--xml", help="comma-separated Mitsuba scene files rendered by both renderers")
    ap.add_argument("-D", "--define", action="append", default=[], metavar="NAME=VALUE",
                    help="a parameter of the --xml files (repeatable)")
    ap.add_argument("--variant", default="scalar_rgb", help="Mitsuba variant for --xml")
    ap.add_argument("--film", help="WxH: the --xml files' film size for both renderers")
    ap.add_argument("--reference-exr", default="", help="comma-separated EXRs, one per --xml file (may be empty)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    binary = caustic_binary(args.binary)
    results = []
    if args.xml:
        results = xml_scenes(binary, args)
    elif args.equal_time:
        results = equal_time(binary, args)
    else:
        modes = args.caustics.split(",")
        if any(m not in ("path", "map") for m in modes):
            sys.exit(f"--caustics: path, map or path,map, not {args.caustics}")
        window = None
        if args.region:
            x0, y0, x1, y1 = (int(v) for v in args.region.split(","))
            window = (slice(y0, y1), slice(x0, x1))
        print(f"caustics: {args.caustics}" + (f", {args.photons} photons" if "map" in modes else "")
              + (f"; region x {x0}..{x1}, y {y0}..{y1}" if window else "")
              + ("; ± standard error from two halves of each image" if args.halves else ""))
        header = f"{'scene':<10} {'caustics':>8} {'caustic spp':>11} {'s':>7} {'mitsuba spp':>11} {'s':>7} {'relMSE':>10}"
        if args.halves:
            header += f" {'noise':>10}"
        header += "  mean ratio R G B"
        if window:
            header += "  region mean ratio R G B"
        print(header)
        for name in args.scenes.split(","):
            d = SCENES[name](args.size)
            theirs, t_theirs, theirs_h = halves_render(lambda spp, seed: render_mitsuba(d, spp, seed=seed),
                                                       args.spp_mitsuba, (0, 1), args.halves)
            save_exr(os.path.join(args.out, f"{name}-mitsuba.exr"), theirs)
            for mode in modes:
                def render(spp, seed):
                    return render_caustic(binary, caustic_scene(d, spp), args.out, name, seed=seed,
                                          caustics=mode, photons=args.photons)
                ours, t_ours, ours_h = halves_render(render, args.spp_caustic, (1, 2), args.halves)
                save_exr(os.path.join(args.out, f"{name}-caustic-{mode}.exr"), ours)
                e, r = relmse(ours, theirs), mean_ratio(ours, theirs)
                row = {"scene": name, "caustics": mode, "photons": args.photons if mode == "map" else None,
                       "caustic_spp": args.spp_caustic, "caustic_seconds": t_ours,
                       "mitsuba_spp": args.spp_mitsuba, "mitsuba_seconds": t_theirs,
                       "relmse": e, "mean_ratio": r}
                line = (f"{name:<10} {mode:>8} {args.spp_caustic:>11} {t_ours:>7.1f} {args.spp_mitsuba:>11} "
                        f"{t_theirs:>7.1f} {e:>10.3e}")
                line += agreement_columns(row, r, theirs, ours_h, theirs_h, args.halves)
                if window:
                    rr = mean_ratio(ours[window], theirs[window])
                    row["region"] = [x0, y0, x1, y1]
                    row["region_mean_ratio"] = rr
                    if args.halves:
                        row["region_mean_ratio_error"] = mean_ratio_error(ours_h, theirs_h, window)
                        line += "  " + " ".join(f"{v:.4f}±{s:.4f}" for v, s in zip(rr, row["region_mean_ratio_error"]))
                    else:
                        line += f"  {rr[0]:.4f} {rr[1]:.4f} {rr[2]:.4f}"
                print(line, flush=True)
                results.append(row)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=2)


def xml_scenes(binary, args):
    """Each --xml file rendered by both renderers, as written (with -D)."""
    if args.variant != "scalar_rgb":
        mi.set_variant(args.variant)
    defines = dict(d.split("=", 1) for d in args.define)
    print(f"Mitsuba {mi.__version__} {mi.variant()}; defines: {defines or 'none'}"
          + (f"; film {args.film}" if args.film else "")
          + ("; ± standard error from two halves of each image" if args.halves else ""))
    print(f"{'scene':<40} {'caustic spp':>11} {'s':>7} {'mitsuba spp':>11} {'s':>7} {'relMSE':>10}"
          + (f" {'noise':>10}" if args.halves else "") + "  mean ratio R G B")
    rows = []
    files = args.xml.split(",")
    refs = args.reference_exr.split(",") if args.reference_exr else [""] * len(files)
    for path, ref_path in zip(files, refs):
        name = os.path.splitext(os.path.basename(path))[0]

        def mitsuba(spp, seed):
            scene = mi.load_file(path, **defines)
            if args.film:
                params = mi.traverse(scene)
                key = next(k for k in params.keys() if k.endswith("film.size"))
                params[key] = mi.ScalarVector2u(*(int(v) for v in args.film.split("x")))
                params.update()
            start = time.time()
            img = mi.render(scene, spp=spp, seed=seed)
            return np.array(img, dtype=np.float64)[:, :, :3], time.time() - start

        def caustic(spp, seed):
            exr = os.path.join(args.out, f"{name}-caustic-part.exr")
            cmd = [binary, "render", path, "--exr", exr, "--quiet", "--seed", str(seed), "--spp", str(spp),
                   "--integrator", "path"]
            for d in args.define:
                cmd += ["-D", d]
            if args.film:
                w, h = args.film.split("x")
                cmd += ["--width", w, "--height", h]
            start = time.time()
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
            wall = time.time() - start
            return np.array(mi.Bitmap(exr), dtype=np.float64)[:, :, :3], wall

        theirs, t_theirs, theirs_h = halves_render(mitsuba, args.spp_mitsuba, (0, 1), args.halves)
        ours, t_ours, ours_h = halves_render(caustic, args.spp_caustic, (1, 2), args.halves)
        save_exr(os.path.join(args.out, f"{name}-mitsuba.exr"), theirs)
        save_exr(os.path.join(args.out, f"{name}-caustic.exr"), ours)
        e, r = relmse(ours, theirs), mean_ratio(ours, theirs)
        row = {"scene": path, "defines": defines, "variant": mi.variant(), "caustic_spp": args.spp_caustic,
               "caustic_seconds": t_ours, "mitsuba_spp": args.spp_mitsuba, "mitsuba_seconds": t_theirs,
               "relmse": e, "mean_ratio": r}
        line = (f"{name:<40} {args.spp_caustic:>11} {t_ours:>7.1f} {args.spp_mitsuba:>11} {t_theirs:>7.1f} "
                f"{e:>10.3e}")
        line += agreement_columns(row, r, theirs, ours_h, theirs_h, args.halves)
        if ref_path:
            ref = np.array(mi.Bitmap(ref_path), dtype=np.float64)[:, :, :3]
            row["reference"] = ref_path
            row["reference_relmse"] = {"caustic": relmse(ours, ref), "mitsuba": relmse(theirs, ref)}
            row["reference_mean_ratio"] = {"caustic": mean_ratio(ours, ref), "mitsuba": mean_ratio(theirs, ref)}
            line += (f"\n    against {os.path.basename(ref_path)}: caustic relMSE {row['reference_relmse']['caustic']:.3e}"
                     f" mean ratio " + " ".join(f"{v:.4f}" for v in row["reference_mean_ratio"]["caustic"])
                     + f"; Mitsuba relMSE {row['reference_relmse']['mitsuba']:.3e} mean ratio "
                     + " ".join(f"{v:.4f}" for v in row["reference_mean_ratio"]["mitsuba"]))
        print(line, flush=True)
        rows.append(row)
    return rows


def equal_time(binary, args):
    """Time against error on the Cornell box: caustic's curve from `caustic
    converge` (spp budgets, render time only), Mitsuba's from `mi.render` at
    the same sample counts (render time only), both against Mitsuba's own
    converged image (`--reference`, else rendered now at --spp-mitsuba)."""
    d = SCENES["cornell"](args.size)
    ref_path = args.reference
    if not ref_path:
        ref_path = os.path.join(args.out, "cornell-reference-mitsuba.exr")
        ref, t = render_mitsuba(d, args.spp_mitsuba, seed=99)
        save_exr(ref_path, ref)
        print(f"reference: Mitsuba {args.spp_mitsuba} spp in {t:.1f} s", flush=True)
    ref = np.array(mi.Bitmap(ref_path), dtype=np.float64)[:, :, :3]
    ladder = [int(x) for x in args.equal_time.split(",")]
    scene = os.path.join(args.out, "cornell-converge.toml")
    with open(scene, "w") as f:
        f.write(caustic_scene(d, 1, seed=5))
    csv = os.path.join(args.out, "cornell-converge.csv")
    subprocess.run([binary, "converge", scene, "--reference", ref_path, "--integrator", "path",
                    "--budgets", ",".join(map(str, ladder)), "--accel", "embree", "--csv", csv, "--quiet"],
                   check=True, stdout=subprocess.DEVNULL)
    rows = []
    ours = []
    with open(csv) as f:
        header = f.readline().strip().split(",")
        for line in f:
            r = dict(zip(header, line.strip().split(",")))
            ours.append((int(r["spp"]), float(r["seconds"]), float(r["relmse"])))
    theirs = []
    for spp in ladder:
        img, wall = render_mitsuba(d, spp, seed=5)
        theirs.append((spp, wall, relmse(img, ref)))
    print(f"{'spp':>6} {'caustic s':>10} {'relMSE':>10} {'mitsuba s':>10} {'relMSE':>10}  "
          f"mitsuba relMSE at caustic's time / caustic relMSE")
    lt = np.log([t for _, t, _ in theirs])
    le = np.log([e for _, _, e in theirs])
    for (spp, t, e), (_, tm, em) in zip(ours, theirs):
        at_time = float(np.exp(np.interp(np.log(t), lt, le))) if lt[0] <= np.log(t) <= lt[-1] else float("nan")
        print(f"{spp:>6} {t:>10.3f} {e:>10.3e} {tm:>10.3f} {em:>10.3e}  {at_time / e:>6.2f}", flush=True)
        rows.append({"spp": spp, "caustic_seconds": t, "caustic_relmse": e,
                     "mitsuba_seconds": tm, "mitsuba_relmse": em,
                     "mitsuba_relmse_at_equal_time": at_time})
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 5), dpi=110)
        ax.loglog([t for _, t, _ in ours], [e for _, _, e in ours], "o-", label="caustic --integrator path (Embree)")
        ax.loglog([t for _, t, _ in theirs], [e for _, _, e in theirs], "s-", label="Mitsuba 3 scalar_rgb, path")
        for (spp, t, e) in ours:
            ax.annotate(str(spp), (t, e), textcoords="offset points", xytext=(4, 4), fontsize=7)
        ax.set_xlabel("render time (s), 2 threads")
        against = "the given reference" if args.reference else f"Mitsuba at {args.spp_mitsuba} spp"
        ax.set_ylabel(f"relMSE (epsilon {EPSILON}) against {against}")
        ax.set_title(f"Cornell box {args.size}x{args.size}: error against time")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(args.plot)
        print(f"written: {args.plot}")
    return rows


if __name__ == "__main__":
    main()
