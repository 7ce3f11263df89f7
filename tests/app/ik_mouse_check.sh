#!/usr/bin/env bash
# The IK chain sample in a real (visible, non-headless) window on the current X display
# (ctest runs under xvfb-run): xdotool grabs the red target with the mouse and drags it;
# the sample's --option report=FILE (target in world and pixels, the chain's effector,
# every 5 frames) must show that the target moved with the mouse and the chain followed.
#   ik_mouse_check.sh PBA_SAMPLES WORKDIR
# Robust on a slow machine: every wait polls the report with a generous hang guard and
# nothing asserts on timing.
set -u
app=$1
work=$2
guard=${PBA_IK_MOUSE_GUARD:-120}   # seconds per wait before giving up

. "$(dirname "$0")/xdo_lib.sh"   # fail, wait_until; checks the display, cleans $work
report=$work/report.txt

# the chain, still until dragged, in a visible window
"$app" --sample "Inverse kinematics/Chain solvers" --size 960x600 --option animate=0 --option bones=10 \
  --option solver=fabrik --option "report=$report" >"$work/app.log" 2>&1 &
pid=$!
trap 'kill $pid 2>/dev/null; wait $pid 2>/dev/null' EXIT

# the window is up and the sample has drawn some frames
find_window
f0=$(field frame)
wait_until "a newer report" 'ge "$(field frame)" $((f0 + 5))'
tx0=$(field target 1); ty0=$(field target 2); tz0=$(field target 3)
px=$(field pixel 1); py=$(field pixel 2)
echo "target at ($tx0, $ty0, $tz0), pixel ($px, $py)"
x0=$(printf '%.0f' "$px"); y0=$(printf '%.0f' "$py")

# press on the target and wait until the sample has grabbed it
xdotool mousemove --window "$wid" "$x0" "$y0"
sleep 0.5
xdotool mousedown 1
wait_until "the grab" 'ge "$(field grabs)" 1'

# drag it in small steps to the left and down
x1=$((x0 - 110)); y1=$((y0 + 45))
drag "$x0" "$y0" "$x1" "$y1"
# the target follows the cursor (its pixel within 4 px of the mouse)
near_mouse='awk -v x="$(field pixel 1)" -v y="$(field pixel 2)" -v mx='$x1' -v my='$y1' "BEGIN {exit !((x - mx)^2 + (y - my)^2 < 16)}"'
wait_until "the target under the mouse at ($x1, $y1)" "$near_mouse"
xdotool mouseup 1

# the chain reaches it: effector within 1 mm of the target
wait_until "the chain to reach the target" 'r=$(field residual); [ -n "$r" ] && ge 0.001 "$r" && ge "$r" 0'
tx=$(field target 1); ty=$(field target 2); tz=$(field target 3)
ex=$(field effector 1); ey=$(field effector 2); ez=$(field effector 3)
echo "after the drag: target ($tx, $ty, $tz), effector ($ex, $ey, $ez), residual $(field residual) m"
moved=$(dist3 "$tx" "$ty" "$tz" "$tx0" "$ty0" "$tz0")
gap=$(dist3 "$tx" "$ty" "$tz" "$ex" "$ey" "$ez")
echo "target moved $moved m; effector to target $gap m"
ge "$moved" 0.05 || fail "the target moved only $moved m"
ge 0.001 "$gap" || fail "the effector is $gap m from the target"
echo "PASS: the mouse moved the target and the chain followed"
