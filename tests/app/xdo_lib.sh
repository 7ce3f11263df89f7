# Shared by the window tests that drive the app with xdotool (sourced, not run). The caller
# sets `work` (its directory, cleaned here), `guard` (seconds per wait) and, once the app is
# started, `pid`.
#   fail MESSAGE       prints FAIL, the last report and the app's output, exits 1
#   wait_until WHAT C  polls the shell condition C until it holds; fails if the app exits
#                      or after the guard

fail() {
  echo "FAIL: $*"
  [ -f "$work/report.txt" ] && echo "last report: $(cat "$work/report.txt")"
  [ -f "$work/app.log" ] && { echo "--- app output ---"; cat "$work/app.log"; }
  exit 1
}

wait_until() {
  local what=$1 cond=$2 t0=$SECONDS
  while ! eval "$cond"; do
    kill -0 $pid 2>/dev/null || fail "the app exited while waiting for $what"
    [ $((SECONDS - t0)) -lt "$guard" ] || fail "timed out after ${guard}s waiting for $what"
    sleep 0.2
  done
}

# start_app ARGS...   starts "$app" ARGS in the background (output to $work/app.log), sets
#                     pid, and kills it when the script exits
start_app() {
  "$app" "$@" >"$work/app.log" 2>&1 &
  pid=$!
  trap 'kill $pid 2>/dev/null; wait $pid 2>/dev/null' EXIT
}

# For the tests that read a sample's --option report=FILE ($report):
#   field NAME [K]     the K-th value (default 1) after NAME in the report
#   ge A B             true when A >= B (numbers)
#   dist3 X Y Z U V W  the distance between two points
#   find_window        waits for the report's frame 10+, sets wid to the app's visible window
#   drag X0 Y0 X1 Y1   moves the mouse from (X0, Y0) to (X1, Y1) in ten steps of 0.15 s
field() { awk -v n="$1" -v k="${2:-1}" '{for (i = 1; i <= NF; ++i) if ($i == n) {print $(i + k); exit}}' "$report" 2>/dev/null; }
ge() { awk -v a="$1" -v b="$2" 'BEGIN {exit !(a + 0 >= b + 0)}'; }
dist3() { awk -v a="$1" -v b="$2" -v c="$3" -v d="$4" -v e="$5" -v f="$6" \
  'BEGIN {printf "%.6f", sqrt((a - d)^2 + (b - e)^2 + (c - f)^2)}'; }
find_window() {
  wait_until "the first frames" '[ -s "$report" ] && ge "$(field frame)" 10'
  wid=$(xdotool search --onlyvisible --name '^pba samples$' 2>/dev/null | head -n 1)
  [ -n "$wid" ] || fail "no visible window named 'pba samples'"
}
drag() {
  local k
  for k in 1 2 3 4 5 6 7 8 9 10; do
    xdotool mousemove --window "$wid" $(($1 + ($3 - $1) * k / 10)) $(($2 + ($4 - $2) * k / 10))
    sleep 0.15
  done
}

# xdotool, retried when the X server refused its connection (an Xvfb in a sandboxed VM now
# and then refuses one connection in ten under load; the next attempt gets through); any
# other failure (a search that finds nothing) returns at once
xdotool() {
  local k rc errf
  errf=$(mktemp)
  for k in 1 2 3 4 5; do
    command xdotool "$@" 2>"$errf"
    rc=$?
    if [ $rc -eq 0 ] || ! grep -q "open display" "$errf"; then break; fi
    sleep 0.2
  done
  cat "$errf" >&2
  rm -f "$errf"
  return $rc
}

# a display and xdotool, then a clean working directory
[ -n "${DISPLAY:-}" ] || fail "DISPLAY is not set (run under xvfb-run, as scripts/test does)"
command -v xdotool >/dev/null || fail "xdotool is not installed (scripts/install-deps)"
rm -rf "$work"
mkdir -p "$work"
