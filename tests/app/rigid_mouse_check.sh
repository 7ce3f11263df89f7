#!/usr/bin/env bash
# A rigid-body sample in a real (visible, non-headless) window on the current X display
# (ctest runs under xvfb-run): xdotool presses on a resting box, drags it up and to the
# side and lets go. The sample's --option report=FILE (the box's centre in world and pixels,
# its velocity, the grabs, every 5 frames) must show that the box was grabbed, followed the
# mouse, and was thrown (still moving once released).
#   rigid_mouse_check.sh PBA_SAMPLES WORKDIR
# Robust on a slow machine: every wait polls the report with a generous hang guard and
# nothing asserts on timing.
set -u
app=$1
work=$2
guard=${PBA_RIGID_MOUSE_GUARD:-120}   # seconds per wait before giving up

. "$(dirname "$0")/xdo_lib.sh"   # fail, wait_until; checks the display, cleans $work
report=$work/report.txt

# the mass-ratio column with equal masses: the report body is its bottom box
"$app" --sample "Rigid bodies/Mass ratio" --size 960x600 --option ratio=1 --option "report=$report" \
  >"$work/app.log" 2>&1 &
pid=$!
trap 'kill $pid 2>/dev/null; wait $pid 2>/dev/null' EXIT

find_window
wait_until "a settled column" 'ge "$(field frame)" 30'
bx0=$(field body 1); by0=$(field body 2); bz0=$(field body 3)
px=$(field pixel 1); py=$(field pixel 2)
echo "box at ($bx0, $by0, $bz0), pixel ($px, $py)"
x0=$(printf '%.0f' "$px"); y0=$(printf '%.0f' "$py")

# press on the box and wait until the sample holds it
xdotool mousemove --window "$wid" "$x0" "$y0"
sleep 0.5
xdotool mousedown 1
wait_until "the grab" 'ge "$(field grabs)" 1 && ge "$(field held)" 1'

# drag it up and to the left in small steps, then hold until the box is near the cursor
x1=$((x0 - 120)); y1=$((y0 - 90))
drag "$x0" "$y0" "$x1" "$y1"
near='awk -v x="$(field pixel 1)" -v y="$(field pixel 2)" -v mx='$x1' -v my='$y1' "BEGIN {exit !((x - mx)^2 + (y - my)^2 < 40^2)}"'
wait_until "the box near the cursor at ($x1, $y1)" "$near"
bx=$(field body 1); by=$(field body 2); bz=$(field body 3)
moved=$(dist3 "$bx" "$by" "$bz" "$bx0" "$by0" "$bz0")
echo "held at ($bx, $by, $bz): moved $moved m, up by $(awk -v a="$by" -v b="$by0" 'BEGIN {print a - b}') m"
ge "$moved" 0.3 || fail "the box moved only $moved m"
ge "$by" "$(awk -v b="$by0" 'BEGIN {print b + 0.2}')" || fail "the box was not lifted (y $by from $by0)"

# a quick flick to the right, then release: the box flies on (thrown) and then falls
xdotool mousemove --window "$wid" $((x1 + 80)) $((y1 - 20))
sleep 0.1
xdotool mouseup 1
wait_until "the release" '[ "$(field held)" = 0 ]'
vx=$(field velocity 1); vy=$(field velocity 2); vz=$(field velocity 3)
speed=$(dist3 "$vx" "$vy" "$vz" 0 0 0)
echo "released at $speed m/s"
ge "$speed" 0.05 || fail "the released box is not moving ($speed m/s)"
echo "PASS: the mouse grabbed, carried and threw the box"
