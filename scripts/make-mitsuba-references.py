#!/usr/bin/env python3
"""Renders the Mitsuba test scenes of tests/data/mitsuba/ with Mitsuba 3
(scalar_rgb) into the references the tests compare caustic's renders with:
NAME.xml -> NAME-mitsuba.exr at the scene's own resolution.

Usage:
  python3 -m pip install mitsuba==3.9.1 numpy
  scripts/make-mitsuba-references.py [--spp 65536] [NAME ...]
"""
import argparse
import glob
import os

import mitsuba as mi

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(ROOT, "tests", "data", "mitsuba")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp", type=int, default=65536)
    ap.add_argument("names", nargs="*", help="scene names (default: every NAME.xml with a reference)")
    args = ap.parse_args()
    mi.set_variant("scalar_rgb")
    names = args.names or [os.path.basename(p)[:-len("-mitsuba.exr")]
                           for p in sorted(glob.glob(os.path.join(DATA, "*-mitsuba.exr")))]
    for name in names:
        scene = mi.load_file(os.path.join(DATA, f"{name}.xml"))
        img = mi.render(scene, spp=args.spp, seed=7)
        out = os.path.join(DATA, f"{name}-mitsuba.exr")
        mi.Bitmap(img).write(out)
        print(f"written: {out} ({args.spp} spp)")


if __name__ == "__main__":
    main()
