#!/usr/bin/env python3
"""OpenCV baseline for `rigctl trace` (host/benches/trace.rs).

Traces the same 600 dpi scan as the Rust bench with a conventional pipeline:
threshold -> connected components for the fiducials -> perspective transform ->
threshold the graphite -> distance-transform ridge (a skeleton at pixel resolution) ->
pixel centres mapped to sheet mm. Prints decode and trace times and the RMS distance of the
centreline points to the truth.

Inputs (written by `cargo bench -p rigctl --bench trace`):
  target/tmp/trace_bench/scan600.png   the scan
  target/tmp/trace_bench/truth.csv     the pencil centreline, closed polyline, x,y mm
Usage: python3 bench/trace_opencv.py [SCAN.png TRUTH.csv]
Needs: pip install opencv-python-headless numpy
"""
import sys
import time
from pathlib import Path

import cv2
import numpy as np

SPACING_MM = 180.0
DOT_MM = (-90.0, 75.0)


def find_fiducials(red, paper):
    black = (red < 0.22 * paper).astype(np.uint8)
    n, _, stats, cents = cv2.connectedComponentsWithStats(black, connectivity=8)
    blobs = []
    for i in range(1, n):
        x, y, w, h, area = stats[i]
        if area < 50 or not 0.75 <= w / h <= 1.33 or not 0.6 <= area / (w * h) <= 0.92:
            continue
        blobs.append((area, cents[i]))
    blobs.sort(key=lambda b: -b[0])
    if len(blobs) < 5:
        raise SystemExit("no fiducials")
    corners = np.array([b[1] for b in blobs[:4]])
    dot = blobs[4][1]
    tl = int(np.argmin(np.linalg.norm(corners - dot, axis=1)))
    others = [i for i in range(4) if i != tl]
    far = max(others, key=lambda i: np.linalg.norm(corners[i] - corners[tl]))
    adj = [i for i in others if i != far]
    # bottom-left: the neighbour the dot points to
    bl = min(adj, key=lambda i: np.linalg.norm(corners[i] - dot))
    tr = [i for i in adj if i != bl][0]
    src = np.float32([corners[tl], corners[tr], corners[far], corners[bl]])
    h = SPACING_MM / 2
    dst = np.float32([[-h, h], [h, h], [h, -h], [-h, -h]])
    return cv2.getPerspectiveTransform(src, dst), src


def trace(img_bgr):
    red = img_bgr[:, :, 2].astype(np.float32)
    paper = float(np.median(red[::8, ::8]))
    H, corners = find_fiducials(red, paper)
    dark = 1.0 - red / paper
    mask = ((dark > 0.2) & (red >= 0.22 * paper)).astype(np.uint8)
    for c in corners:  # blank the fiducials' antialiased rims
        cv2.circle(mask, (int(c[0]), int(c[1])), int(0.05 * np.linalg.norm(corners[0] - corners[1])), 0, -1)
    dist = cv2.distanceTransform(mask, cv2.DIST_L2, 5)
    ridge = (dist >= cv2.dilate(dist, np.ones((3, 3), np.uint8))) & (dist >= 2.0)
    ys, xs = np.nonzero(ridge)
    pts = np.stack([xs + 0.5, ys + 0.5], axis=1).astype(np.float64).reshape(-1, 1, 2)
    return cv2.perspectiveTransform(pts, H).reshape(-1, 2)


def distances(points, truth):
    """Distance of each point to the closed polyline `truth`."""
    a = truth
    b = np.roll(truth, -1, axis=0)
    out = np.empty(len(points))
    for k in range(0, len(points), 2000):
        p = points[k:k + 2000]
        nearest = np.argmin(((p[:, None, :] - a[None, :, :]) ** 2).sum(-1), axis=1)
        best = np.full(len(p), np.inf)
        for off in (-2, -1, 0, 1):
            i = (nearest + off) % len(a)
            d = b[i] - a[i]
            t = np.clip(((p - a[i]) * d).sum(1) / (d * d).sum(1), 0, 1)
            best = np.minimum(best, np.linalg.norm(p - a[i] - t[:, None] * d, axis=1))
        out[k:k + 2000] = best
    return out


def main():
    base = Path(__file__).resolve().parent.parent / "target/tmp/trace_bench"
    scan = Path(sys.argv[1]) if len(sys.argv) > 1 else base / "scan600.png"
    truth_csv = Path(sys.argv[2]) if len(sys.argv) > 2 else base / "truth.csv"
    t0 = time.perf_counter()
    img = cv2.imread(str(scan), cv2.IMREAD_COLOR)
    t1 = time.perf_counter()
    if img is None:
        raise SystemExit(f"cannot read {scan}; run `cargo bench -p rigctl --bench trace` first")
    runs = []
    for _ in range(3):
        s = time.perf_counter()
        pts = trace(img)
        runs.append(time.perf_counter() - s)
    truth = np.loadtxt(truth_csv, delimiter=",", skiprows=1)
    d = distances(pts, truth)
    print(f"opencv {cv2.__version__}: {img.shape[1]}x{img.shape[0]} px")
    print(f"decode   {1000 * (t1 - t0):8.1f} ms")
    print(f"trace    {1000 * min(runs):8.1f} ms (best of 3)")
    print(f"points   {len(pts)} (unordered ridge pixels)")
    print(f"rms      {np.sqrt((d ** 2).mean()):.4f} mm, max {d.max():.4f} mm")


if __name__ == "__main__":
    main()
