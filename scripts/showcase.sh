#!/usr/bin/env bash
# The three showcase renders at the original report's settings (1920×1080,
# 20 spp): cornell with 1M photons, underwater with 100M, dragon with 10M,
# with each accelerator. Prints wall time, the render summary and peak RSS.
# Usage: scripts/showcase.sh [OUT_DIR] [ACCELS...]   (default: showcase embree kdtree)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-showcase}
shift || true
accels=("$@")
[ ${#accels[@]} -eq 0 ] && accels=(embree kdtree)
mkdir -p "$out"
cargo build --release --quiet
for accel in "${accels[@]}"; do
  for spec in cornell:1000000 underwater:100000000 dragon:10000000; do
    scene=${spec%%:*}
    photons=${spec##*:}
    echo "== $scene, $photons photons, $accel (load: $(cut -d' ' -f1-3 /proc/loadavg))"
    /usr/bin/time -f "wall %e s, user %U s, peak RSS %M KiB" \
      ./target/release/caustic render "scenes/$scene.toml" --photons "$photons" --accel "$accel" \
      --quiet -o "$out/$scene-$accel.png" 2>&1 | grep -v '^written'
  done
done
