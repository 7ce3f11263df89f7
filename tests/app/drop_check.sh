#!/usr/bin/env bash
# Drag and drop in a real (visible) window on the current X display (ctest runs under
# xvfb-run): xdnd_drop, an XDND drag source, drops a file that is not a scene (the app says
# so and stays on its sample), then a scene file, which opens in the "Scene file" sample:
# the app announces the file, and F12's screenshot is named after that sample.
#   drop_check.sh PBA_SAMPLES XDND_DROP WORKDIR SCENE.json
# Every wait polls with a generous hang guard; nothing asserts on timing.
set -u
app=$1
dropper=$2
work=$3
scene=$4
guard=${PBA_DROP_GUARD:-120}   # seconds per wait before giving up

. "$(dirname "$0")/xdo_lib.sh"   # fail, wait_until; checks the display, cleans $work
cd "$work" || fail "cannot enter $work"

# the default sample (Dynamics/Integrators) in a visible window
"$app" --size 960x600 >"$work/app.log" 2>&1 &
pid=$!
trap 'kill $pid 2>/dev/null; wait $pid 2>/dev/null' EXIT

wait_until "the window" 'xdotool search --onlyvisible --name "^pba samples$" >/dev/null 2>&1'
wid=$(xdotool search --onlyvisible --name '^pba samples$' | head -n 1)
sleep 2

# a file that is not a scene: refused with a message, the app runs on
echo "not a scene" >notes.txt
"$dropper" "$wid" 480 300 notes.txt >>"$work/drop.log" 2>&1 || fail "xdnd_drop: $(cat "$work/drop.log")"
wait_until "the refusal of notes.txt" 'grep -q "notes.txt: drop a scene file (.json) to open it" app.log'
kill -0 $pid 2>/dev/null || fail "the app quit after a dropped text file"

# the scene file: opened in the Scene file sample
"$dropper" "$wid" 480 300 "$scene" >>"$work/drop.log" 2>&1 || fail "xdnd_drop: $(cat "$work/drop.log")"
name=$(basename "$scene")
wait_until "the app to open $name" 'grep -q "Particles/Scene file: opened .*/$name" app.log'

# F12 names its screenshot after the sample on screen: the Scene file sample
xdotool windowfocus --sync "$wid" 2>/dev/null || xdotool windowfocus "$wid"
sleep 1
xdotool key F12
wait_until "the screenshot" 'ls screenshots/*.png >/dev/null 2>&1'
ls screenshots/particles_scene_file_000.png >/dev/null 2>&1 ||
  fail "the screenshot after the drop is $(ls screenshots), not the Scene file sample's"
echo "PASS: the dropped scene file $name opened in the Scene file sample"
