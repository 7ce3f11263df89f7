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

expect 0 "usage: pba <command>" --help
expect 0 "usage: pba lab" lab --help
expect 2 "missing command"
expect 2 "unknown command 'frobnicate'" frobnicate
expect 2 "unknown flag '--bogus' for 'pba lab'" lab --bogus
expect 2 "--method: unknown integrator 'rk5'; valid names: euler, semi-implicit-euler, verlet" lab --method rk5
expect 2 "--problem: unknown problem 'moon'; valid names: projectile" lab --problem moon
expect 2 "--steps: expected an integer, got '1e3x'" lab --steps 1e3x
expect 2 "--steps: must be in [1, 1000000000], got 0" lab --steps 0
expect 2 "--steps: must be in [1, 1000000000], got -5" lab --steps -5
expect 2 "--out: missing value" lab --out
mkdir -p "$tmp.d" && : > "$tmp.d/file"
expect 2 "--out: cannot create directory '$tmp.d/file/sub'" lab --out "$tmp.d/file/sub"
rm -rf "$tmp.d"
rm -rf "$tmp"
expect 0 "Velocity Verlet" lab --problem oscillator --method velocity-verlet --method rk4 --steps 2000 --out "$tmp" --no-plot
for f in convergence.csv orders.csv energy.csv stability.csv energy_summary.csv; do
  [ -s "$tmp/$f" ] || { echo "FAIL: $tmp/$f missing"; fail=1; }
done
rm -rf "$tmp"
exit $fail
