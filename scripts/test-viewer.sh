#!/usr/bin/env bash
# The viewer in a real window on a machine without GPU or display: starts
# `caustic view scenes/cornell.toml` under Xvfb (Mesa's software OpenGL),
# waits for the rendered image, takes a screenshot, presses `p`, takes
# another, and checks that the first shows the Cornell box (not a blank or
# black window) and that the second differs from it where the photon cloud
# is drawn; then `k` for the KD-tree boxes.
#
# Usage: scripts/test-viewer.sh [caustic binary]   (default target/release/caustic)
# Screenshots are kept in target/viewer-test/. Installs xvfb, xdotool,
# ImageMagick and Mesa from Debian's packages when they are missing (as root).
set -euo pipefail
cd "$(dirname "$0")/.."

BIN=${1:-target/release/caustic}
OUT=target/viewer-test
mkdir -p "$OUT"

need=()
command -v Xvfb >/dev/null || need+=(xvfb)
command -v xdotool >/dev/null || need+=(xdotool)
command -v import >/dev/null && command -v compare >/dev/null || need+=(imagemagick)
command -v xwininfo >/dev/null || need+=(x11-utils)
# OpenGL (Mesa llvmpipe) and the X libraries winit opens at run time.
for lib in libGL.so.1 libEGL.so.1 libxkbcommon-x11.so.0 libXcursor.so.1 libXi.so.6 libXrandr.so.2; do
  ldconfig -p | grep -q "$lib" || need+=(libgl1 libegl1 libgl1-mesa-dri libglx-mesa0 libxkbcommon-x11-0 libxcursor1 libxi6 libxrandr2)
done
if [ ${#need[@]} -gt 0 ]; then
  echo "installing: ${need[*]}"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${need[@]}" >/dev/null
fi
[ -x "$BIN" ] || { echo "no binary at $BIN (cargo build --release)"; exit 1; }

DISPLAY_NUM=:$((90 + RANDOM % 9))
Xvfb "$DISPLAY_NUM" -screen 0 1400x800x24 -nolisten tcp >"$OUT/xvfb.log" 2>&1 &
XVFB_PID=$!
VIEW_PID=
cleanup() {
  [ -n "$VIEW_PID" ] && kill "$VIEW_PID" 2>/dev/null || true
  kill "$XVFB_PID" 2>/dev/null || true
  wait 2>/dev/null || true
}
trap cleanup EXIT
export DISPLAY=$DISPLAY_NUM
export LIBGL_ALWAYS_SOFTWARE=1
for _ in $(seq 50); do xdpyinfo >/dev/null 2>&1 && break; sleep 0.1; done

# 4 samples per pixel: the image is finished (and stops changing) in seconds.
"$BIN" view scenes/cornell.toml --spp 4 >"$OUT/view.log" 2>&1 &
VIEW_PID=$!

WID=$(timeout 60 xdotool search --sync --name "^caustic .*cornell.toml" | head -n1) || {
  echo "FAIL: no viewer window"; cat "$OUT/view.log"; exit 1; }
eval "$(xdotool getwindowgeometry --shell "$WID")" # X, Y, WIDTH, HEIGHT
echo "window $WID at ${X},${Y} ${WIDTH}x${HEIGHT}"

shot() { import -window root -crop "${WIDTH}x${HEIGHT}+${X}+${Y}" +repage "$1"; }
# The image is right of the panel (about 340 px wide): this region of it.
IMAGE_REGION="600x400+420+40"
stat() { convert "$1" -crop "$IMAGE_REGION" +repage -colorspace gray -format "%[fx:mean] %[fx:standard_deviation]\n" info:; }

# Wait until the image is rendered and stable (two equal screenshots).
prev=
for i in $(seq 120); do
  shot "$OUT/poll.png"
  read -r mean sd < <(stat "$OUT/poll.png")
  if awk -v m="$mean" -v s="$sd" 'BEGIN { exit !(m > 0.05 && s > 0.05) }'; then
    if [ -n "$prev" ] && [ "$(compare -metric AE "$OUT/poll.png" "$prev" null: 2>&1 || true)" = "0" ]; then
      break
    fi
    cp "$OUT/poll.png" "$OUT/prev.png"; prev="$OUT/prev.png"
  fi
  sleep 1
done
sleep 1
shot "$OUT/render.png"
read -r mean sd < <(stat "$OUT/render.png")
echo "rendered image: mean $mean, standard deviation $sd"
awk -v m="$mean" -v s="$sd" 'BEGIN { exit !(m > 0.05 && s > 0.05) }' || {
  echo "FAIL: the image is blank or black"; cat "$OUT/view.log"; exit 1; }
# The Cornell box's side walls: red on the left of the image, green on the right.
red=$(convert "$OUT/render.png" -crop 60x200+570+150 +repage -format "%[fx:mean.r-mean.g]" info:)
green=$(convert "$OUT/render.png" -crop 60x200+1010+150 +repage -format "%[fx:mean.g-mean.r]" info:)
echo "left wall red-green $red, right wall green-red $green"
awk -v r="$red" -v g="$green" 'BEGIN { exit !(r > 0.1 && g > 0.05) }' || {
  echo "FAIL: no red and green walls where the Cornell box has them"; exit 1; }

# `p`: the photon cloud. There is no window manager: give the window the
# keyboard focus ourselves, with the pointer over the image.
xdotool mousemove $((X + 800)) $((Y + 300))
xdotool windowfocus --sync "$WID"
sleep 0.5
# overlay NAME SECONDS WHAT: after the keys just sent, wait, take NAME.png
# and require more than 500 pixels to differ from the rendered image.
overlay() {
  sleep "$2"
  shot "$OUT/$1.png"
  local changed
  changed=$(compare -metric AE -fuzz 10% "$OUT/render.png" "$OUT/$1.png" null: 2>&1 || true)
  echo "pixels changed by the $3: $changed"
  [ "${changed%%.*}" -gt 500 ] || { echo "FAIL: no $3 drawn"; exit 1; }
}
xdotool key p
overlay photons 2 "photon overlay ('p')"
xdotool key p
xdotool key k
overlay kdtree 3 "KD-tree boxes ('k')"

kill -0 "$VIEW_PID" || { echo "FAIL: the viewer exited"; cat "$OUT/view.log"; exit 1; }
echo "viewer window test passed (screenshots in $OUT)"
