#!/usr/bin/env python3
"""Splits a `perf record` profile of a caustic render into the parts of a
path sample: ray queries (Embree, the accelerators and the analytic shapes'
tests), surface interaction, BSDF, light sampling, sampler, accumulation
(the tile loop, film and camera rays), the path loop itself, and other.

usage: perf record -F 499 -g -o OUT.data caustic render SCENE --spp 32 --threads 2 --integrator path
       scripts/profile-split.py OUT.data [--top 15]

Self time per function (`perf report --no-children`), summed by the first
rule that matches its library and name.
"""
import argparse
import re
import subprocess

RULES = [
    ("ray queries", r"libembree|caustic::accel::|::intersect\b|::occluded\b|rtcIntersect|rtcOccluded|nearest_hit"),
    ("surface interaction", r"surface_interaction"),
    ("BSDF", r"caustic::bsdf::"),
    ("light sampling", r"caustic::scene::light::|caustic::integrator::lights::"),
    ("sampler", r"caustic::math::sampler::|caustic::math::rng::|sobol_burley"),
    ("accumulation", r"render_tile_pass|PixelSamples|caustic::film::|FnMut|caustic::integrator::render::"),
    ("path loop", r"caustic::integrator::path::"),
    ("libm (sincos, atan…)", r"libm\.so"),
    ("kernel", r"\[kernel"),
]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("data")
    ap.add_argument("--top", type=int, default=15)
    args = ap.parse_args()
    out = subprocess.run(["perf", "report", "-i", args.data, "--no-children", "--sort", "dso,symbol", "--stdio",
                          "-g", "none", "--percent-limit", "0"], capture_output=True, text=True, check=True).stdout
    parts, top = {}, []
    for line in out.splitlines():
        m = re.match(r"\s*([0-9.]+)%\s+(\S+)\s+\[[.k]\]\s+(.*?)\s*$", line)
        if not m:
            continue
        pct, dso, sym = float(m.group(1)), m.group(2), m.group(3)
        name = f"{dso} {sym}"
        part = next((p for p, r in RULES if re.search(r, name)), "other")
        parts[part] = parts.get(part, 0.0) + pct
        top.append((pct, part, sym if "libembree" not in dso else "(Embree)"))
    order = [p for p, _ in RULES] + ["other"]
    print("| " + " | ".join(order) + " |")
    print("| " + " | ".join("---" for _ in order) + " |")
    print("| " + " | ".join(f"{parts.get(p, 0.0):.1f} %" for p in order) + " |")
    print()
    for pct, part, sym in sorted(top, reverse=True)[:args.top]:
        print(f"{pct:6.2f} %  {part:22} {sym[:100]}")


if __name__ == "__main__":
    main()
