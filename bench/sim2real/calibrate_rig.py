#!/usr/bin/env python3
"""How bench/sim2real/highway_rig.yaml's numbers were found (prints them; evaluation data only:
../shared/realdata/cars_highway, never copied into the repository).

1. distortion: on car-free frames, the yellow edge line near the camera (a straight line along
   the road, which the side-facing camera sees as a horizontal line) is traced column by
   column; k1 and k2 (OpenCV, fx = fy = 338: fov_x 90) are fitted so that every frame's traced
   points, undistorted, lie on one straight line each (rms in pixels).
2. horizon and camera height: for side-view boxes of boxes.csv (wider than twice their height,
   not cut by the image's border) the car's length from its undistorted box is
   width_px x camera_height / (bottom row - horizon row) (fx cancels). The horizon is the row
   where that length does not depend on the distance (the slope of log length on log rows
   below the horizon crosses 0); the camera height makes the median length 4.6 m.
3. --check: `synthgen calibrate` on every 5th frame with cars, boxes.csv as labels, and a tally
   of the cars it finds "not a car's size there" (too wide or too narrow for a car along the road).

    PYTHONPATH=python .venv/bin/python bench/sim2real/calibrate_rig.py [--check [--rig RIG.yaml]]
"""
from __future__ import annotations

import argparse
import csv
import glob
import os
import re
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image
from scipy.optimize import minimize_scalar

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
HIGHWAY = os.path.join(REPO, "..", "shared", "realdata", "cars_highway")
FX = FY = 338.0
CX, CY = 338.0, 190.0
TYPICAL_LENGTH = 4.6


def undistort(u, v, k1, k2):
    """Pixel -> undistorted pixel (OpenCV radial model, fixed-point inversion)."""
    xd, yd = (np.asarray(u, float) - CX) / FX, (np.asarray(v, float) - CY) / FY
    x, y = xd.copy(), yd.copy()
    for _ in range(80):
        r2 = x * x + y * y
        s = 1 + k1 * r2 + k2 * r2 * r2
        x, y = xd / s, yd / s
    return x * FX + CX, y * FY + CY


def yellow_lines():
    """Per car-free frame whose yellow line crosses > 550 columns: its traced (u, v) points."""
    lines = []
    for f in sorted(glob.glob(os.path.join(HIGHWAY, "negatives", "*.jpg"))):
        a = np.asarray(Image.open(f).convert("RGB")).astype(float)
        r, g, b = a[..., 0], a[..., 1], a[..., 2]
        yel = (r > 120) & (g > 90) & (b < 0.6 * r) & (r - b > 60) & (np.abs(r - g) < 70)
        yel[:200] = False
        us, vs = [], []
        for u in range(0, a.shape[1], 4):
            rows = np.nonzero(yel[:, u])[0]
            if 1 <= len(rows) <= 6:
                us.append(u)
                vs.append(rows.mean())
        us, vs = np.array(us, float), np.array(vs, float)
        if len(us) < 120:
            continue
        keep = np.abs(np.polyval(np.polyfit(us, vs, 2), us) - vs) < 3
        if keep.sum() < 120 or np.ptp(us[keep]) < 550:
            continue
        lines.append((os.path.basename(f), us[keep], vs[keep]))
    return lines


def line_rms(lines, k1, k2):
    err = []
    for _, us, vs in lines:
        x, y = undistort(us, vs, k1, k2)
        A = np.c_[x, np.ones_like(x)]
        c = np.linalg.lstsq(A, y, rcond=None)[0]
        err.append(A @ c - y)
    return float(np.sqrt(np.mean(np.concatenate(err) ** 2)))


def folds(k1, k2, corner):
    r = np.linspace(0, 3, 30001)
    rd = r * (1 + k1 * r * r + k2 * r ** 4)
    bad = np.nonzero(np.diff(rd) <= 0)[0]
    return len(bad) > 0 and rd[bad[0]] * FX < corner


def side_boxes():
    rows = list(csv.DictReader(open(os.path.join(HIGHWAY, "boxes.csv"))))
    a = np.array([[float(r[k]) for k in ("xmin", "ymin", "xmax", "ymax")] for r in rows])
    w, h = a[:, 2] - a[:, 0], a[:, 3] - a[:, 1]
    return a[(a[:, 0] > 2) & (a[:, 2] < 674) & (w / h > 2.0)]


def check(rig):
    """synthgen calibrate on every 5th frame with cars: (labelled, too wide, too narrow)."""
    with tempfile.TemporaryDirectory() as tmp:
        cal = os.path.join(tmp, "rig.yaml")
        with open(rig) as f, open(cal, "w") as g:
            g.write(f.read() + "\nlabels:\n  - {file: %s, format: csv, class: car}\n"
                    % os.path.abspath(os.path.join(HIGHWAY, "boxes.csv")))
        n = wide = narrow = 0
        pat = re.compile(r"its box is (\d+) px wide, .* turned along the road (\d+) to (\d+) px there")
        env = dict(os.environ, PYTHONPATH=os.path.join(REPO, "python"))
        for img in sorted(glob.glob(os.path.join(HIGHWAY, "images", "*.jpg")))[::5]:
            out = subprocess.run([sys.executable, "-m", "synthgen", "calibrate", img, "--calibration", cal,
                                  "-o", os.path.join(tmp, "p.png")], env=env, capture_output=True, text=True).stdout
            for m in pat.finditer(out):
                w, lo, hi = map(int, m.groups())
                n += 1
                wide += w > hi
                narrow += w < lo
        return n, wide, narrow


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="run synthgen calibrate on every 5th frame with cars")
    ap.add_argument("--rig", default=os.path.join(HERE, "highway_rig.yaml"), help="the rig --check checks")
    args = ap.parse_args()
    lines = yellow_lines()
    print(f"yellow lines traced: {len(lines)} frames; rms off straight with no distortion {line_rms(lines, 0, 0):.2f} px")
    best = None
    corner = float(np.hypot(CX, CY))
    for k2 in np.arange(0.0, 0.101, 0.005):
        r = minimize_scalar(lambda k: line_rms(lines, k, k2), bounds=(-0.4, 0.0), method="bounded")
        if not folds(r.x, k2, corner) and (best is None or r.fun < best[2]):
            best = (r.x, k2, r.fun)
    k1, k2, rms = best
    print(f"distortion_k1={k1:.3f} distortion_k2={k2:.3f} line_rms_px={rms:.2f}")
    a = side_boxes()
    ul, vl = undistort(a[:, 0], a[:, 3], k1, k2)
    ur, vr = undistort(a[:, 2], a[:, 3], k1, k2)
    vb, ww = np.maximum(vl, vr), ur - ul
    print(f"side-view boxes used: {len(a)}")
    for hor in range(170, 190):
        _, hu = undistort(np.array([CX]), np.array([float(hor)]), k1, k2)
        d = vb - hu[0]
        length = ww / d
        slope = np.polyfit(np.log(d), np.log(length), 1)[0]
        print(f"  horizon {hor}: slope {slope:+.3f}, camera height for a median length of "
              f"{TYPICAL_LENGTH} m: {TYPICAL_LENGTH / np.median(length):.2f} m")
    if args.check:
        n, wide, narrow = check(args.rig)
        print(f"calibrate_cars={n} calibrate_too_wide={wide} calibrate_too_narrow={narrow}")


if __name__ == "__main__":
    main()
