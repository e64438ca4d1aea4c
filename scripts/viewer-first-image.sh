#!/usr/bin/env bash
# Time to first image of the viewer in a real window: starts `caustic view
# SCENE` under Xvfb (Mesa's software OpenGL) and takes a screenshot every
# 0.2 s until the image area (right of the panel) stops being blank; prints
# the seconds from launch to the window and to that first image, and keeps
# the screenshot.
#
# Usage: scripts/viewer-first-image.sh SCENE [caustic binary] [view flags...]
#        (default binary target/release/caustic; needs what
#        scripts/test-viewer.sh installs: Xvfb, xdotool, ImageMagick, Mesa)
# Output: target/viewer-first-image/first.png (and the viewer's log).
set -euo pipefail
cd "$(dirname "$0")/.."

SCENE=${1:?usage: $0 SCENE [caustic binary] [view flags...]}
BIN=${2:-target/release/caustic}
shift $(( $# >= 2 ? 2 : 1 ))
OUT=target/viewer-first-image
mkdir -p "$OUT"
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

start=$(date +%s.%N)
"$BIN" view "$SCENE" "$@" >"$OUT/view.log" 2>&1 &
VIEW_PID=$!
WID=$(timeout 300 xdotool search --sync --name "^caustic " | head -n1) || {
  echo "FAIL: no viewer window"; cat "$OUT/view.log"; exit 1; }
window=$(date +%s.%N)
eval "$(xdotool getwindowgeometry --shell "$WID")" # X, Y, WIDTH, HEIGHT
# The image is right of the panel (about 340 px wide).
REGION="$((WIDTH - 420))x$((HEIGHT - 80))+$((X + 400))+$((Y + 40))"
for _ in $(seq 1500); do
  import -window root -crop "$REGION" +repage "$OUT/poll.png"
  sd=$(convert "$OUT/poll.png" -colorspace gray -format "%[fx:standard_deviation]" info:)
  if awk -v s="$sd" 'BEGIN { exit !(s > 0.02) }'; then
    first=$(date +%s.%N)
    import -window root -crop "${WIDTH}x${HEIGHT}+${X}+${Y}" +repage "$OUT/first.png"
    awk -v a="$start" -v w="$window" -v f="$first" \
      'BEGIN { printf "window after %.2f s, first image after %.2f s (screenshot: '"$OUT"'/first.png)\n", w - a, f - a }'
    exit 0
  fi
  sleep 0.2
done
echo "FAIL: no image within 300 s"; cat "$OUT/view.log"; exit 1
