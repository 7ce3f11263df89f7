#!/usr/bin/env bash
# R (restart) keeps the step rate the command line gave: a rigid-body sample started with
# --dt 0.01 in a real (visible) window on the current X display (ctest runs under xvfb-run)
# reports its tick length (--option report=FILE, "dt"); after xdotool presses R the new
# sample must report dt 0.01 again (before, its constructor's 1/60 s won at every restart).
#   restart_check.sh PBA_SAMPLES WORKDIR
# Every wait polls the report with a generous hang guard; nothing asserts on timing.
set -u
app=$1
work=$2
guard=${PBA_RESTART_GUARD:-120}   # seconds per wait before giving up

. "$(dirname "$0")/xdo_lib.sh"   # fail, wait_until; checks the display, cleans $work
report=$work/report.txt

"$app" --sample "Rigid bodies/Mass ratio" --size 960x600 --dt 0.01 --option "report=$report" \
  >"$work/app.log" 2>&1 &
pid=$!
trap 'kill $pid 2>/dev/null; wait $pid 2>/dev/null' EXIT

find_window
dt0=$(field dt)
echo "started: dt $dt0"
[ "$dt0" = 0.01 ] || fail "--dt 0.01 gave dt $dt0 at the start"
wait_until "frame 60" 'ge "$(field frame)" 60'
xdotool windowfocus --sync "$wid" 2>/dev/null || xdotool windowfocus "$wid"
xdotool key r
# the new sample counts its frames from 0 again
wait_until "the restart" '! ge "$(field frame)" 60'
wait_until "frames after the restart" 'ge "$(field frame)" 10'
dt1=$(field dt)
echo "restarted: dt $dt1"
[ "$dt1" = 0.01 ] || fail "after R the sample runs at dt $dt1, not the command line's 0.01"
echo "PASS: R kept the command line's step"
