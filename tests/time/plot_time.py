#!/usr/bin/python3
"""Plots for docs/time-stepping.md from a real run of the time-stepping tests.

    PBA_TIME_SWEEP_CSV=/tmp/sweep.csv PBA_TIME_SPIRAL_CSV=/tmp/spiral.csv \
        build/release/tests/time/test_time --gtest_filter='TimeStall.*'
    /usr/bin/python3 tests/time/plot_time.py /tmp/sweep.csv /tmp/spiral.csv docs/img
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLORS = {"per-frame": "#e5484d", "max-step": "#f76b15", "fixed": "#3e63dd"}


def read(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def sweep_plot(rows, out):
    # one line per strategy against the render delay
    by = defaultdict(list)
    for r in rows:
        by[r["strategy"]].append(r)
    fig, ax = plt.subplots(1, 3, figsize=(13, 3.8))
    for name, rs in by.items():
        d = [float(r["delay_ms"]) for r in rs]
        ax[0].plot(d, [float(r["ticks_per_frame"]) for r in rs], label=name, color=COLORS[name])
        ax[1].plot(d, [float(r["tick_dt_ms"]) for r in rs], label=name, color=COLORS[name])
        ax[2].plot(d, [100 * float(r["dropped_fraction"]) for r in rs], label=name,
                   color=COLORS[name])
    ax[0].set_ylabel("ticks per frame (mean)")
    ax[1].set_ylabel("simulated time per tick (ms)")
    ax[2].set_ylabel("real time dropped (%)")
    for a in ax:
        a.set_xlabel("artificial render delay per frame (ms)")
        a.grid(alpha=0.3)
    ax[0].legend()
    fig.suptitle("Render delay sweep: ticks cost 4 ms; fixed_dt = max_dt = 1/60 s; "
                 "cap 4 ticks per frame; max_frame_dt 0.25 s")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def spiral_plot(rows, out):
    # frame time per frame, with and without the tick cap
    fig, ax = plt.subplots(figsize=(6.5, 3.8))
    for cap, label, color in (("100000", "no cap: the physics stall", "#e5484d"),
                              ("4", "cap of 4 ticks per frame", "#3e63dd")):
        rs = [r for r in rows if r["cap"] == cap]
        ax.semilogy([int(r["frame"]) for r in rs], [float(r["frame_ms"]) for r in rs],
                    label=label, color=color, marker=".")
    ax.set_xlabel("frame")
    ax.set_ylabel("frame time (ms, log)")
    ax.set_title("Ticks cost 20 ms, simulate 16.7 ms (fixed strategy)")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    sweep, spiral, outdir = sys.argv[1:4]
    sweep_plot(read(sweep), f"{outdir}/time_render_delay.png")
    spiral_plot(read(spiral), f"{outdir}/time_spiral.png")
