#!/usr/bin/env bash
# The Cloth on a falling box sample in a real (visible, non-headless) window on the current X
# display (ctest runs under xvfb-run): once the box has landed and the cloth lies on it,
# xdotool presses on the cloth's middle over the box's top (the cloth, nearer the eye than
# the box there, is what the press takes) and pulls it up and aside: the cloth comes off the
# box, which stays on the ground. The sample's --option report=FILE gives the box's centre,
# the cloth's centre of mass and its middle particle (world and pixels) every 5 frames.
#   cloth_box_check.sh PBA_SAMPLES WORKDIR
# Every wait polls the report with a generous hang guard; nothing asserts on timing.
set -u
app=$1
work=$2
guard=${PBA_CLOTH_BOX_GUARD:-120}   # seconds per wait before giving up

. "$(dirname "$0")/xdo_lib.sh"   # fail, wait_until, start_app, field, ge, find_window, drag
report=$work/report.txt

start_app --sample "Rigid bodies/Cloth on a falling box" --size 960x600 --option "report=$report"

find_window
# landed and draped: the box rests on the ground (centre 0.5 m up) and the cloth over it
wait_until "the box on the ground" 'ge "$(field frame)" 150 && ge 0.52 "$(field body 2)"'
by0=$(field body 2); cy0=$(field cloth 2)
echo "box at y = $by0, cloth's centre of mass at y = $cy0"
ge "$cy0" "$by0" || fail "the cloth is not above the box's centre"

# press on the cloth's middle (on the box's top) and pull it up and to the side: the cloth
# comes off the box
px=$(printf '%.0f' "$(field clothpx 1)"); py=$(printf '%.0f' "$(field clothpx 2)")
mx0=$(field middle 1); my0=$(field middle 2); mz0=$(field middle 3)
xdotool mousemove --window "$wid" "$px" "$py"
sleep 0.5
xdotool mousedown 1
sleep 0.5
drag "$px" "$py" $((px + 220)) $((py - 60))
moved='ge "$(dist3 "$(field middle 1)" "$(field middle 2)" "$(field middle 3)" "$mx0" "$my0" "$mz0")" 0.5'
wait_until "the cloth's middle pulled 0.5 m" "$moved"
wait_until "the cloth's centre of mass off the box's middle" 'ge "$(field cloth 1)" 0.3'
xdotool mouseup 1
bx=$(field body 1); by=$(field body 2)
echo "cloth's centre of mass now at x = $(field cloth 1); the box at ($bx, $by)"
ge 0.52 "$by" || fail "the box left the ground"
grep -q "Cloth on a falling box: the box landed" "$work/app.log" || fail "no report of the landing"
echo "PASS: the mouse pulled the cloth off the box it had landed on"
