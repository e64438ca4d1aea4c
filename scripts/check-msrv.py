#!/usr/bin/env python3
"""Checks that Cargo.toml's `rust-version` is honest.

It must be at least the newest `rust-version` any locked dependency declares
(read from `cargo metadata`, for the main crate and for the fuzz crate, whose
lockfile is its own), and the installed toolchain must be at least that
version. Prints the dependencies that set the floor; exits 1 when the
declared version is too low or the toolchain too old.

    scripts/check-msrv.py            # from the repository root
"""

import json
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent


def version(text):
    """'1.88' or '1.88.0' as a comparable tuple of three integers."""
    parts = [int(p) for p in text.split(".")]
    return tuple(parts + [0] * (3 - len(parts)))


def show(v):
    return ".".join(str(p) for p in v)


def metadata(manifest):
    out = subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--locked", "--manifest-path", str(manifest)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return json.loads(out)


def main():
    declared = None
    needs = []  # (version, package, version string, lockfile)
    for manifest in [ROOT / "Cargo.toml", ROOT / "fuzz" / "Cargo.toml"]:
        meta = metadata(manifest)
        members = set(meta["workspace_members"])
        for p in meta["packages"]:
            if p["name"] == "caustic" and p["source"] is None:
                declared = version(p["rust_version"])
                continue
            if p["id"] in members or not p.get("rust_version"):
                continue
            needs.append((version(p["rust_version"]), p["name"], p["version"], str(manifest.parent.relative_to(ROOT) / "Cargo.lock")))
    if declared is None:
        sys.exit("check-msrv: no `rust-version` in Cargo.toml")
    floor = max(n[0] for n in needs)
    rustc = subprocess.run(["rustc", "--version"], check=True, capture_output=True, text=True).stdout
    installed = version(re.match(r"rustc (\d+\.\d+\.\d+)", rustc).group(1))
    setters = sorted({f"{name} {v}" for (req, name, v, _) in needs if req == floor})
    print(
        f"rust-version {show(declared)}; newest locked dependency needs {show(floor)} "
        f"({', '.join(setters)}); rustc {show(installed)}"
    )
    ok = True
    if declared < floor:
        print(f"check-msrv: Cargo.toml declares rust-version {show(declared)}, but these locked dependencies need more:")
        for req, name, v, lock in sorted(needs, reverse=True):
            if req > declared:
                print(f"  {name} {v} needs {show(req)} ({lock})")
        ok = False
    if installed < declared:
        print(f"check-msrv: rustc {show(installed)} is older than the declared rust-version {show(declared)}")
        ok = False
    if installed[:2] == declared[:2]:
        print("check-msrv: the installed toolchain is the declared rust-version: this CI run builds at it")
    else:
        print(f"check-msrv: note: the builds of this run use rustc {show(installed)}, newer than {show(declared)}")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
