#!/usr/bin/env python3
"""`pba lab` plots are saved at a resolution where their smallest text can be read.

Runs a small lab (one problem, two methods), then reads each PNG's pHYs chunk (the
resolution matplotlib saved it at) and its size, and checks that the smallest text the
script draws (plot_lab.SMALLEST_PT points, legends and notes) is at least 12 pixels tall:
pt * dpi / 72 >= 12, i.e. a legible ~9 px x-height. The old 72 dpi with 5.5 pt legends
gave 5.5 px. Usage: test_plots.py <pba> <tools-dir> <scratch-dir>
"""
import os
import shutil
import struct
import subprocess
import sys
import zlib

pba, tools, scratch = sys.argv[1:4]
sys.path.insert(0, tools)
import plot_lab  # noqa: E402

shutil.rmtree(scratch, ignore_errors=True)
r = subprocess.run([pba, "lab", "--problem", "oscillator", "--method", "rk4", "--method", "euler",
                    "--steps", "2000", "--out", scratch, "--quiet"], capture_output=True, text=True)
print(r.stdout, r.stderr)
assert r.returncode == 0, f"pba lab exited {r.returncode}"


def png_info(path):
    """(width, height, dpi) from the IHDR and pHYs chunks; dpi None without pHYs"""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG"
    pos, width, height, dpi = 8, 0, 0, None
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        assert zlib.crc32(kind + body) == struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])[0], "bad CRC"
        if kind == b"IHDR":
            width, height = struct.unpack(">II", body[:8])
        elif kind == b"pHYs":
            ppx, ppy, unit = struct.unpack(">IIB", body)
            if unit == 1:  # pixels per metre
                dpi = ppx * 0.0254
        pos += 12 + n
    return width, height, dpi


fail = 0
for name in ("lab_convergence.png", "lab_energy.png", "lab_stability.png"):
    path = os.path.join(scratch, name)
    if not os.path.exists(path):
        print(f"FAIL: {path} missing")
        fail = 1
        continue
    w, h, dpi = png_info(path)
    text_px = plot_lab.SMALLEST_PT * (dpi or 0) / 72
    ok = dpi is not None and text_px >= 12
    print(f"{'ok' if ok else 'FAIL'}: {name} {w}x{h} px at {dpi and round(dpi)} dpi: "
          f"smallest text {plot_lab.SMALLEST_PT} pt = {text_px:.1f} px (need >= 12)")
    fail |= not ok
shutil.rmtree(scratch, ignore_errors=True)
sys.exit(fail)
