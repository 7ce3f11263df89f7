#!/usr/bin/env bash
# The Card house sample in a real (visible, non-headless) window on the current X display
# (ctest runs under xvfb-run): the tower stands, the K key (xdotool) throws the ball that
# knocks it down; after R (restart) it stands again, and the mouse pulls its crown card off
# sideways. The sample's --option report=FILE gives the crown card's centre (world and
# pixels) every 5 frames.
#   card_house_check.sh PBA_SAMPLES WORKDIR
# Every wait polls the report with a generous hang guard; nothing asserts on timing.
set -u
app=$1
work=$2
guard=${PBA_CARD_HOUSE_GUARD:-120}   # seconds per wait before giving up

. "$(dirname "$0")/xdo_lib.sh"   # fail, wait_until, start_app, field, ge, find_window, drag
report=$work/report.txt

start_app --sample "Rigid bodies/Card house" --size 960x600 --option "report=$report"

find_window
xdotool windowfocus --sync "$wid" 2>/dev/null || xdotool windowfocus "$wid"

# standing: the crown card stays put (to 1 mm) for 60 frames once settled
settled() {
  wait_until "a settled tower" 'ge "$(field frame)" '"$1"
  y0=$(field body 2)
  local f=$(($(field frame) + 60))
  wait_until "60 more frames" 'ge "$(field frame)" '"$f"
  y1=$(field body 2)
  echo "crown card at y = $y0, then $y1"
  ge "$(awk -v a="$y0" -v b="$y1" 'BEGIN {print 0.001 - (a > b ? a - b : b - a)}')" 0 ||
    fail "the tower does not stand: the crown card moved from $y0 to $y1"
}
settled 90

# K throws the ball: the crown comes down by more than half a card
xdotool key k
wait_until "the knocked tower to fall" 'ge "$(awk -v a="$y0" -v b="$(field body 2)" "BEGIN {print a - b}")" 0.5'
grep -q "Card house: fell" "$work/app.log" || fail "no 'fell' line after the knock"
echo "the K key knocked it down: crown card at y = $(field body 2)"

# R restarts the sample (a new report from frame 0): it stands again
f=$(field frame)
xdotool key r
wait_until "the restart" '[ "$(field frame)" -lt '"$f"' ]'
settled 90

# the mouse: press on the crown card and pull it sideways; it comes off and falls
px=$(printf '%.0f' "$(field pixel 1)"); py=$(printf '%.0f' "$(field pixel 2)")
xdotool mousemove --window "$wid" "$px" "$py"
sleep 0.5
xdotool mousedown 1
wait_until "the grab" 'ge "$(field grabs)" 1 && ge "$(field held)" 1'
drag "$px" "$py" $((px + 200)) $((py - 20))
xdotool mouseup 1
wait_until "the release" '[ "$(field held)" = 0 ]'
wait_until "the crown card to fall" 'ge "$(awk -v a="$y0" -v b="$(field body 2)" "BEGIN {print a - b}")" 0.5'
echo "PASS: the K key and the mouse knocked the standing card house down"
