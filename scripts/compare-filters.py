#!/usr/bin/env python3
"""Pixel filters against Mitsuba 3: the image of a straight emitter edge.

An emitting rectangle covers the left half of a 32 x 4 image, its edge 0.32
pixel right of a pixel centre; each column's value is the filter's step
response there. Renders the same scene with caustic (`--caustic`, default
target/release/caustic) and Mitsuba 3 (`pip install mitsuba numpy`, variant
scalar_rgb) for the box, tent and Gaussian filters with Mitsuba's default
widths, and prints both profiles and their largest difference.
"""
import argparse
import pathlib
import subprocess
import tempfile

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

WIDTH, HEIGHT = 32, 4
# Pixel 15's centre is at x = -1/32 on the plane z = -1 (fov 90 across x).
EDGE = -1.0 / 32.0 + 0.02

XML = """<scene version="3.0.0">
 <integrator type="path"><integer name="max_depth" value="2"/></integrator>
 <sensor type="perspective"><float name="fov" value="90"/><string name="fov_axis" value="x"/>
  <transform name="to_world"><lookat origin="0,0,0" target="0,0,-1" up="0,1,0"/></transform>
  <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
  <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>
   <rfilter type="{filter}"/></film>
 </sensor>
 <shape type="rectangle"><transform name="to_world"><translate x="{cx}" y="0" z="-1"/></transform>
  <emitter type="area"><rgb name="radiance" value="1,1,1"/></emitter></shape>
</scene>
"""

TOML = """[render]
width = {w}
height = {h}
spp = {spp}
integrator = "path"
[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
fov = 90
fov_axis = "x"
filter = "{filter}"
[[lights]]
type = "area"
position = [{cx}, 0.0, -1.0]
u = [2.0, 0.0, 0.0]
v = [0.0, 2.0, 0.0]
colour = [1.0, 1.0, 1.0]
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--caustic", default="target/release/caustic")
    ap.add_argument("--spp", type=int, default=4096)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        print("| filter | columns 14-17, caustic | columns 14-17, Mitsuba | largest difference |")
        print("|---|---|---|---|")
        for name in ["box", "tent", "gaussian"]:
            values = dict(filter=name, spp=args.spp, w=WIDTH, h=HEIGHT, cx=EDGE - 1.0)
            (tmp / "s.xml").write_text(XML.format(**values))
            (tmp / "s.toml").write_text(TOML.format(**values))
            ref = np.array(mi.render(mi.load_file(str(tmp / "s.xml"))))[..., 0].mean(axis=0)
            subprocess.run(
                [args.caustic, "render", str(tmp / "s.toml"), "--exr", str(tmp / "c.exr"), "-o", str(tmp / "c.png")],
                check=True,
                stdout=subprocess.DEVNULL,
            )
            ours = np.array(mi.Bitmap(str(tmp / "c.exr")))[..., 0].mean(axis=0)
            fmt = lambda a: " ".join(f"{x:.3f}" for x in a[14:18])
            print(f"| {name} | {fmt(ours)} | {fmt(ref)} | {abs(ours - ref).max():.4f} |")


if __name__ == "__main__":
    main()
