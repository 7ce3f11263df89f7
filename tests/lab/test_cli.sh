#!/bin/sh
# `pba` command-line checks: help works, bad flags and unknown names give a clear message
# naming the flag and value with exit code 2 (never a crash), and a small lab run writes
# its CSVs. Usage: test_cli.sh <path-to-pba> <scratch-dir>
pba=$1
tmp=$2
fail=0

# expect <exit code> <text the output must contain> <args...>
expect() {
  want=$1 text=$2
  shift 2
  out=$("$pba" "$@" 2>&1)
  code=$?
  if [ "$code" -ne "$want" ]; then
    echo "FAIL: pba $*: exit $code, want $want"; echo "$out"; fail=1
  elif ! printf '%s' "$out" | grep -qF -- "$text"; then
    echo "FAIL: pba $*: output lacks '$text'"; echo "$out"; fail=1
  else
    echo "ok: pba $* -> $code"
  fi
}

expect 0 "usage: pba [OPTIONS] [SUBCOMMAND]" --help
expect 0 "usage: pba lab" lab --help
expect 0 "usage: pba run" run --help
# --version prints the project version (from CMake) at every level
expect 0 "pba 0." --version
expect 0 "pba lab 0." lab --version
expect 0 "pba run 0." run --version
expect 2 "missing command"
expect 2 "unknown command 'frobnicate'" frobnicate
expect 2 "pba lab: unknown flag '--bogus'" lab --bogus
expect 2 "pba lab: unknown flag '--bogus'" lab --bogus=3
expect 2 "--method: unknown integrator 'rk5'; valid names: euler, semi-implicit-euler, verlet" lab --method rk5
expect 2 "--problem: unknown problem 'moon'; valid names: projectile" lab --problem moon
expect 2 "--steps: expected an integer, got '1e3x'" lab --steps 1e3x
expect 2 "--steps: must be in [1, 1000000000], got 0" lab --steps 0
expect 2 "--steps: must be in [1, 1000000000], got -5" lab --steps -5
# --flag=value is the same as --flag value
expect 2 "--steps: must be in [1, 1000000000], got 0" lab --steps=0
expect 2 "--method: unknown integrator 'rk5'" lab --method=rk5
expect 2 "--out: missing value" lab --out
mkdir -p "$tmp.d" && : > "$tmp.d/file"
expect 2 "--out: cannot create directory '$tmp.d/file/sub'" lab --out "$tmp.d/file/sub"
rm -rf "$tmp.d"
rm -rf "$tmp"
expect 0 "Velocity Verlet" lab --problem oscillator --method velocity-verlet --method=rk4 --steps 2000 --out="$tmp" --no-plot
for f in convergence.csv orders.csv energy.csv stability.csv energy_summary.csv; do
  [ -s "$tmp/$f" ] || { echo "FAIL: $tmp/$f missing"; fail=1; }
done
rm -rf "$tmp"

# progress on stderr: lines when it is not a terminal (every PBA_PROGRESS_INTERVAL
# seconds), the last at 100%: 2 methods x (convergence + energy) + 2 stability scans;
# none with --quiet
err=$(PBA_PROGRESS_INTERVAL=1e-9 "$pba" lab --problem oscillator --method rk4 --method euler --steps 2000 \
      --out "$tmp" --no-plot 2>&1 >/dev/null)
if printf '%s' "$err" | grep -q "pba lab: 6/6 measurements (100%), .* measurements/s, 0.0 s left"; then
  echo "ok: pba lab progress lines"
else
  echo "FAIL: pba lab progress: '$err'"; fail=1
fi
err=$(PBA_PROGRESS_INTERVAL=1e-9 "$pba" lab --problem oscillator --method rk4 --steps 2000 --out "$tmp" \
      --no-plot --quiet 2>&1 >/dev/null)
if [ -z "$err" ]; then echo "ok: pba lab --quiet prints no progress"; else echo "FAIL: pba lab --quiet: '$err'"; fail=1; fi
rm -rf "$tmp"
exit $fail
