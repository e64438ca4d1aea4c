#!/usr/bin/env python3
"""Copies a folder of Mitsuba scenes (with its include/ and meshes/
folders) to OUT and gives every mesh file shape `face_normals` = true, in the
scenes and their includes, so that both renderers shade the meshes with
their geometric normals.

Why: caustic's OBJ reader keeps a file's vertex normals only when each
position has one normal, and otherwise recomputes smooth normals, where
Mitsuba keeps the file's normal of each corner (a floor and a wall meeting
at an edge, as the backdrop of Mitsuba's participating_media test scenes,
then shade differently). With face normals both renderers see the same
surfaces, which isolates what a comparison is about (docs/validation.md,
"Participating media").

Usage:
  scripts/mitsuba-face-normals.py SRC_DIR OUT_DIR
A relative `<path value>` in the files is made absolute (to SRC_DIR), so the
copies find the same textures.
"""
import os
import re
import shutil
import sys


def main():
    src, out = sys.argv[1], sys.argv[2]
    shutil.copytree(src, out, dirs_exist_ok=True)
    for root, _, files in os.walk(out):
        for name in files:
            if not name.endswith(".xml"):
                continue
            path = os.path.join(root, name)
            os.chmod(path, 0o644)
            text = open(path).read()
            text = re.sub(r'(<string name="filename" value="[^"]+\.(obj|ply|serialized)"\s*/>)',
                          r'\1<boolean name="face_normals" value="true"/>', text)
            rel_src = os.path.join(src, os.path.relpath(root, out))
            text = re.sub(r'<path value="([^"/][^"]*)"\s*/>',
                          lambda m: f'<path value="{os.path.normpath(os.path.join(rel_src, m.group(1)))}"/>', text)
            open(path, "w").write(text)
            print(f"written: {path}")


if __name__ == "__main__":
    main()
