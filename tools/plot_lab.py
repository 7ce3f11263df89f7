#!/usr/bin/env python3
"""Plot the integrator lab's CSVs (written by `pba lab --out DIR`) as PNGs in DIR.

    python3 tools/plot_lab.py DIR

Makes lab_convergence.png (global error at t_end against dt, log-log, one panel per
problem, with reference slopes 1, 2 and 4), lab_energy.png (relative energy error against
time over the long runs, log |dE/E0|) and lab_stability.png (spectral radius of one step
on x'' = -x against omega*dt). Needs matplotlib (Debian: python3-matplotlib).
"""
import csv
import math
import os
import sys
from collections import OrderedDict

COLORS = {  # one colour per method, shared by every plot
    "euler": "#d62728",
    "semi-implicit-euler": "#ff7f0e",
    "verlet": "#2ca02c",
    "velocity-verlet": "#17becf",
    "rk4": "#1f77b4",
    "implicit-euler": "#9467bd",
}
STYLES = {"verlet": "--", "velocity-verlet": ":"}
# Resolution and the smallest text: legends and notes are SMALLEST_PT points, so
# SMALLEST_PT * DPI / 72 pixels tall (7 pt at 160 dpi: 15.6 px, readable; 5.5 pt at the
# old 72 dpi was 5.5 px). The test tests/lab/test_plots.py holds the PNGs to this.
DPI = 160
SMALLEST_PT = 7


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def grouped(rows, *keys):
    """rows grouped by the tuple of `keys`, keeping first-seen order"""
    out = OrderedDict()
    for r in rows:
        out.setdefault(tuple(r[k] for k in keys), []).append(r)
    return out


def grid(n):
    cols = 4 if n > 6 else 3 if n > 4 else n
    rows = (n + cols - 1) // cols
    return rows, cols


def why_no_order(note):
    # the lab's note for a NaN order, as the summary table's one word
    if note.startswith("diverged"):
        return "diverged"
    if note.startswith("the error does not"):
        return "no conv."
    if note.startswith("too few usable points"):
        return "too few"
    if note.startswith("error below the closed form"):
        return "-"
    return "exact"


def plot_convergence(plt, d):
    rows = read(os.path.join(d, "convergence.csv"))
    order_rows = read(os.path.join(d, "orders.csv"))
    orders = {(r["problem"], r["method"]): r["observed_order"] for r in order_rows}
    notes = {(r["problem"], r["method"]): r.get("note", "") for r in order_rows}
    problems = list(grouped(rows, "problem"))
    nr, nc = grid(len(problems))
    fig, axes = plt.subplots(nr, nc, figsize=(3.6 * nc, 3.0 * nr), squeeze=False)
    for ax, (prob,) in zip(axes.flat, problems):
        lo_dt, hi_dt, lo_e, hi_e = math.inf, 0, math.inf, 0
        for (p, m), pts in grouped(rows, "problem", "method").items():
            if p != prob:
                continue
            dt = [float(r["dt"]) for r in pts]
            err = [float(r["error"]) for r in pts]
            keep = [(a, b) for a, b in zip(dt, err) if math.isfinite(b) and b > 0]
            if not keep:
                continue
            o = orders.get((p, m), "nan")
            lab = f"{m} ({float(o):.2f})" if o not in ("nan", "") else f"{m} ({why_no_order(notes.get((p, m), ''))})"
            ax.loglog(*zip(*keep), STYLES.get(m, "-"), marker="o", ms=2.5, lw=1.2,
                      color=COLORS.get(m), label=lab)
            lo_dt, hi_dt = min(lo_dt, min(dt)), max(hi_dt, max(dt))
            lo_e, hi_e = min(lo_e, min(b for _, b in keep)), max(hi_e, max(b for _, b in keep))
        # reference slopes anchored at the top-right of the data
        if hi_dt > 0:
            for p_ref in (1, 2, 4):
                xs = [lo_dt, hi_dt]
                ys = [hi_e * (x / hi_dt) ** p_ref for x in xs]
                ax.loglog(xs, ys, color="grey", lw=0.6, alpha=0.6)
                ax.text(lo_dt, max(ys[0], lo_e), f" slope {p_ref}", fontsize=SMALLEST_PT, color="grey",
                        va="bottom")
            ax.set_ylim(max(lo_e / 3, 1e-17), hi_e * 3)
        ax.set_title(prob, fontsize=9)
        ax.set_xlabel("dt (s)", fontsize=8)
        ax.set_ylabel("error at t_end", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=SMALLEST_PT, loc="lower right")
        ax.grid(True, which="major", lw=0.3)
    for ax in list(axes.flat)[len(problems):]:
        ax.axis("off")
    fig.suptitle("Global error against step size (observed order in brackets)", fontsize=10)
    fig.tight_layout()
    out = os.path.join(d, "lab_convergence.png")
    fig.savefig(out, dpi=DPI)
    plt.close(fig)
    return out


def plot_energy(plt, d):
    rows = read(os.path.join(d, "energy.csv"))
    problems = list(grouped(rows, "problem"))
    nr, nc = grid(len(problems))
    fig, axes = plt.subplots(nr, nc, figsize=(3.6 * nc, 3.0 * nr), squeeze=False)
    for ax, (prob,) in zip(axes.flat, problems):
        dt = None
        for (p, m), pts in grouped(rows, "problem", "method").items():
            if p != prob:
                continue
            dt = pts[0]["dt"]
            t = [float(r["t"]) for r in pts[1:]]
            e = [abs(float(r["rel_energy_error"])) for r in pts[1:]]
            keep = [(a, max(b, 1e-17)) for a, b in zip(t, e) if math.isfinite(b)]
            if keep:
                ax.loglog(*zip(*keep), STYLES.get(m, "-"), lw=1.0, color=COLORS.get(m), label=m)
        # keep a runaway method (explicit Euler's e^100) from flattening the others
        lo, hi = ax.get_ylim()
        if hi > 1e3:
            ax.set_ylim(lo, 1e3)
            ax.text(0.02, 0.97, "clipped at 1e3", transform=ax.transAxes, fontsize=SMALLEST_PT, va="top",
                    color="grey")
        ax.set_title(f"{prob} (dt = {float(dt):.3g} s)" if dt else prob, fontsize=9)
        ax.set_xlabel("t (s)", fontsize=8)
        ax.set_ylabel("|E - E_ref| / |E0|", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=SMALLEST_PT, loc="best")
        ax.grid(True, which="major", lw=0.3)
    for ax in list(axes.flat)[len(problems):]:
        ax.axis("off")
    fig.suptitle("Energy error over the long runs", fontsize=10)
    fig.tight_layout()
    out = os.path.join(d, "lab_energy.png")
    fig.savefig(out, dpi=DPI)
    plt.close(fig)
    return out


def plot_stability(plt, d):
    rows = read(os.path.join(d, "stability.csv"))
    fig, ax = plt.subplots(figsize=(6, 3.6))
    for (m,), pts in grouped(rows, "method").items():
        z = [float(r["omega_dt"]) for r in pts]
        rho = [float(r["spectral_radius"]) for r in pts]
        lim = float(pts[0]["limit"])
        lab = f"{m} (limit {lim:.3f})" if math.isfinite(lim) else f"{m} (no limit)"
        ax.plot(z, rho, STYLES.get(m, "-"), lw=1.2, color=COLORS.get(m), label=lab)
    ax.axhline(1.0, color="black", lw=0.6)
    ax.set_ylim(0, 2.5)
    ax.set_xlabel("omega * dt", fontsize=8)
    ax.set_ylabel("spectral radius of one step", fontsize=8)
    ax.set_title("Stability on x'' = -omega^2 x: unstable where the curve is above 1", fontsize=9)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=SMALLEST_PT, loc="upper left")
    ax.grid(True, lw=0.3)
    fig.tight_layout()
    out = os.path.join(d, "lab_stability.png")
    fig.savefig(out, dpi=DPI)
    plt.close(fig)
    return out


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if len(argv) == 2 else 2
    d = argv[1]
    if not os.path.isfile(os.path.join(d, "convergence.csv")):
        print(f"plot_lab.py: {d}: no convergence.csv here (run `pba lab --out {d}` first)",
              file=sys.stderr)
        return 2
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("plot_lab.py: matplotlib is not installed (apt-get install python3-matplotlib)",
              file=sys.stderr)
        return 1
    outs = [plot_convergence(plt, d)]
    if os.path.isfile(os.path.join(d, "energy.csv")):
        outs.append(plot_energy(plt, d))
    if os.path.isfile(os.path.join(d, "stability.csv")):
        outs.append(plot_stability(plt, d))
    for o in outs:
        print(f"wrote {o}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
