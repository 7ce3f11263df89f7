#!/usr/bin/env bash
# The app's keys in a real (visible) window on the current X display (ctest runs under
# xvfb-run), pressed with xdotool:
#   F12 saves the frame to screenshots/<sample>_NNN.png in the working directory;
#   F1 hides the panels; then two screenshots a second apart differ while the sample runs
#   and are identical after Space paused it (the 3D view stands still);
#   with a menu open, Esc closes it and the app keeps running; a second Esc quits (exit 0).
#   keys_check.sh PBA_SAMPLES WORKDIR
# Every wait polls with a generous hang guard; nothing asserts on timing.
set -u
app=$1
work=$2
guard=${PBA_KEYS_GUARD:-120}   # seconds per wait before giving up

. "$(dirname "$0")/xdo_lib.sh"   # fail, wait_until; checks the display, cleans $work
cd "$work" || fail "cannot enter $work"

# the default sample (Dynamics/Integrators, always moving) in a visible window
"$app" --size 960x600 >"$work/app.log" 2>&1 &
pid=$!
trap 'kill $pid 2>/dev/null; wait $pid 2>/dev/null' EXIT

shots() { ls screenshots/*.png 2>/dev/null | wc -l; }
# press KEY and wait for screenshot number N to be written
shot() {
  xdotool key "$1"
  wait_until "screenshot $2" '[ "$(shots)" -ge '"$2"' ]'
  sleep 0.3
}

wait_until "the window" 'xdotool search --onlyvisible --name "^pba samples$" >/dev/null 2>&1'
wid=$(xdotool search --onlyvisible --name '^pba samples$' | head -n 1)
xdotool windowfocus --sync "$wid" 2>/dev/null || xdotool windowfocus "$wid"
sleep 2

# F12: a screenshot, announced on stdout
shot F12 1
grep -q "pba_samples: screenshot .*screenshots/dynamics_integrators_000.png" app.log ||
  fail "F12 did not announce screenshots/dynamics_integrators_000.png"

# panels off, then two shots a second apart: the running sample moves between them
xdotool key F1
sleep 1
shot F12 2
sleep 1
shot F12 3
cmp -s screenshots/dynamics_integrators_001.png screenshots/dynamics_integrators_002.png &&
  fail "two screenshots a second apart are identical while the sample runs"

# Space pauses: after it, two shots a second apart are the same picture
xdotool key space
sleep 1.5
shot F12 4
sleep 1
shot F12 5
cmp -s screenshots/dynamics_integrators_003.png screenshots/dynamics_integrators_004.png ||
  fail "Space did not pause: two screenshots a second apart differ"

# panels on, open the Samples menu with the mouse; Esc closes it and the app runs on
xdotool key F1
sleep 1
xdotool mousemove --window "$wid" 36 10 click 1
sleep 1.5
xdotool key Escape
sleep 2
kill -0 $pid 2>/dev/null || fail "Esc with the Samples menu open quit the app (it should close the menu)"

# a second Esc quits, with exit code 0
xdotool key Escape
t0=$SECONDS
while kill -0 $pid 2>/dev/null; do
  [ $((SECONDS - t0)) -lt "$guard" ] || fail "the app did not quit on Esc"
  sleep 0.2
done
wait $pid
rc=$?
trap - EXIT
[ $rc -eq 0 ] || fail "the app exited with $rc after Esc"
echo "PASS: F12 saved screenshots, Space paused, Esc closed the menu and then quit"
