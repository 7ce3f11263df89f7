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

# a display and xdotool, then a clean working directory
[ -n "${DISPLAY:-}" ] || fail "DISPLAY is not set (run under xvfb-run, as scripts/test does)"
command -v xdotool >/dev/null || fail "xdotool is not installed (scripts/install-deps)"
rm -rf "$work"
mkdir -p "$work"
