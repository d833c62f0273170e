#!/usr/bin/env python3
"""A third sheet renderer for `rigctl trace`, written from FORMATS.md alone (numpy + OpenCV +
scipy), sharing nothing with the project's two Rust renderers: the sheet's primitives are
mapped point by point through a pinhole camera (principal point at the image centre, or off it
with --centre-off-px as in a cropped photo; radial
distortion k1 on normalised coordinates) or a scanner's similarity, then rasterised by
sub-pixel sampling (4 x 4 per pixel: a pencil sub-sample is inked within half the local width
of the centreline's nearest point, a disc's inside its mapped outline). Pencil: a circle of
40-90 mm radius centred 2-40 mm off the printed one, a line of 110-170 mm turned 0-30 deg and
offset 2-40 mm, or a free wiggle (three sines); 3-8 skips of 1-6 mm; darkness 0.35-0.7 varying
along the path (scans: half of them faint, 0.18-0.3), multiplied by the paper's tooth; dust
and fibres; photos at 200-300 px per sheet inch, tilted up to 40 deg, k1 within +-0.08, a light
gradient and a soft shadow, blur, noise, JPEG q85-95; scans at 300 / 600 dpi, PNG.

Each image is traced with `rigctl trace IMAGE --out CSV`; one JSON line per image gives the exit
code, the coverage (share of the true centreline within 0.1 mm of the written polyline) and the
RMS distance of the written points to the true centreline; a summary line counts the images
that meet the bars of docs/trace.md and the exits 0 below 0.95 coverage.

Usage: python3 bench/trace_render3.py KIND MEDIUM FIRST_SEED COUNT [--rig PATH] [--out DIR]
  KIND: circle | line | free; MEDIUM: photo | scan300 | scan600
Needs: pip install numpy opencv-python-headless scipy matplotlib
"""
import argparse
import json
import math
import os
import subprocess

import cv2
import numpy as np

RMS_BAR_MM = {"photo": 0.03, "scan300": 0.02, "scan600": 0.015}


def path_truth(rng, kind):
    if kind == "circle":
        r = rng.uniform(40, 90)
        d = rng.uniform(2, 40)
        a = rng.uniform(0, 2 * np.pi)
        c = np.array([d * math.cos(a), d * math.sin(a)])
        # keep inside the trace area
        lim = np.array([104.0, 107.0]) - r
        c = np.clip(c, -lim, lim)
        t = np.linspace(0, 2 * np.pi, int(2 * np.pi * r / 0.01))
        a0 = rng.uniform(0, 2 * np.pi)
        pts = np.stack([c[0] + r * np.cos(t + a0), c[1] + r * np.sin(t + a0)], 1)
        return pts, True
    if kind == "line":
        ang = math.radians(rng.uniform(0, 30)) * rng.choice([-1, 1])
        L = rng.uniform(110, 170)
        off = rng.uniform(2, 40) * rng.choice([-1, 1])
        u = np.array([math.cos(ang), math.sin(ang)])
        n = np.array([-u[1], u[0]])
        s = np.linspace(-L / 2, L / 2, int(L / 0.01))
        pts = off * n + s[:, None] * u
        return pts, False
    # free curve: a wiggle along a turned axis
    ang = math.radians(rng.uniform(-30, 30))
    L = rng.uniform(110, 160)
    s = np.linspace(-L / 2, L / 2, int(L / 0.01) * 2)
    y = np.zeros_like(s)
    for k in range(3):
        y += rng.uniform(3, 12) * np.sin(2 * np.pi * s / rng.uniform(40, 120) + rng.uniform(0, 6))
    y += rng.uniform(-30, 30)
    u = np.array([math.cos(ang), math.sin(ang)])
    n = np.array([-u[1], u[0]])
    pts = s[:, None] * u + y[:, None] * n
    return pts, False


def arclen(p):
    return np.concatenate([[0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])


class Cam:
    def __init__(self, rng, photo, ppmm, centre_off_px=0.0):
        self.photo = photo
        if photo:
            tilt = math.radians(rng.uniform(0, 40))
            az = rng.uniform(0, 2 * np.pi)
            roll = rng.uniform(-np.pi, np.pi)
            self.k1 = rng.uniform(-0.08, 0.08)
            D = 400.0
            # camera centre above the sheet, tilted by `tilt` towards azimuth `az`
            C = np.array([D * math.sin(tilt) * math.cos(az), D * math.sin(tilt) * math.sin(az), D * math.cos(tilt)])
            zc = -C / np.linalg.norm(C)  # looks at origin
            up = np.array([math.cos(roll), math.sin(roll), 0.0])
            xc = np.cross(up, zc); xc /= np.linalg.norm(xc)
            yc = np.cross(zc, xc)
            self.R = np.stack([xc, yc, zc])  # world -> camera rows
            self.C = C
            self.f = ppmm * D
        else:
            self.k1 = 0.0
            self.rot = rng.uniform(-np.pi, np.pi) if rng.random() < 0.3 else rng.uniform(-0.05, 0.05)
            self.f = ppmm
        # image size from the sheet's corners (+- 112 mm), then a margin
        corners = np.array([[x, y] for x in (-120, 120) for y in (-150, 150)], float)
        self.c = np.zeros(2)
        q = self.project(corners)
        if self.photo:
            # the principal point at the image centre, or (--centre-off-px, a photo cropped off
            # its centre) 0.5-1 times that far from it in a random direction
            off = np.zeros(2)
            if centre_off_px > 0:
                a = rng.uniform(0, 2 * np.pi)
                off = rng.uniform(0.5, 1.0) * centre_off_px * np.array([math.cos(a), math.sin(a)])
            half = np.abs(q).max(0) + 40 + np.abs(off)
            self.c = half + off
            self.size = (int(2 * half[0]), int(2 * half[1]))
        else:
            lo, hi = q.min(0), q.max(0)
            self.c = -lo + 40
            self.size = (int(hi[0] - lo[0] + 80), int(hi[1] - lo[1] + 80))

    def project(self, p):
        p = np.asarray(p, float)
        if not self.photo:
            c, s = math.cos(self.rot), math.sin(self.rot)
            x = self.f * (c * p[:, 0] - s * p[:, 1])
            y = -self.f * (s * p[:, 0] + c * p[:, 1])
            return np.stack([x, y], 1) + self.c
        P = np.concatenate([p, np.zeros((len(p), 1))], 1) - self.C
        q = P @ self.R.T
        xn, yn = q[:, 0] / q[:, 2], q[:, 1] / q[:, 2]
        r2 = xn * xn + yn * yn
        g = 1 + self.k1 * r2
        return np.stack([self.f * xn * g, self.f * yn * g], 1) + self.c

    def scale_at(self, p):
        p = np.asarray(p, float)[None]
        a = self.project(p); b = self.project(p + [[0.1, 0]]); c = self.project(p + [[0, 0.1]])
        return 0.5 * (np.hypot(*(b - a)[0]) + np.hypot(*(c - a)[0])) / 0.1


SUB = (np.arange(4) + 0.5) / 4  # sub-pixel samples; pixel (i, j) covers [i, i+1) x [j, j+1)


def fill_disc(layer, cam, c, r, val):
    from matplotlib.path import Path
    t = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    q = cam.project(np.stack([c[0] + r * np.cos(t), c[1] + r * np.sin(t)], 1))
    x0, y0 = np.floor(q.min(0)).astype(int) - 1
    x1, y1 = np.ceil(q.max(0)).astype(int) + 1
    H, W = layer.shape
    x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, W), min(y1, H)
    if x1 <= x0 or y1 <= y0:
        return
    xs = (np.arange(x0, x1)[:, None] + SUB[None, :]).ravel()
    ys = (np.arange(y0, y1)[:, None] + SUB[None, :]).ravel()
    X, Y = np.meshgrid(xs, ys)
    inside = Path(q).contains_points(np.stack([X.ravel(), Y.ravel()], 1)).reshape(len(ys), len(xs))
    cov = inside.reshape(y1 - y0, 4, x1 - x0, 4).mean(axis=(1, 3))
    sub = layer[y0:y1, x0:x1]
    np.maximum(sub, np.round(cov * val).astype(np.uint8), out=sub)


def stroke(layer, cam, truth, keep, dark, width_mm):
    """Supersampled pencil: a sub-sample is inked when within half the local width of the
    drawn centreline (nearest dense point), with that point's darkness."""
    from scipy.spatial import cKDTree
    pts = truth[keep]
    q = cam.project(pts)
    # local scale across the stroke: px per mm along the normal
    t = np.gradient(pts, axis=0)
    t /= np.linalg.norm(t, axis=1)[:, None] + 1e-12
    nrm = np.stack([-t[:, 1], t[:, 0]], 1)
    qs = cam.project(pts + 0.05 * nrm)
    half_px = 0.5 * width_mm[keep] * np.hypot(*(qs - q).T) / 0.05
    H, W = layer.shape
    mask = np.zeros((H, W), np.uint8)
    reach = int(np.ceil(2 * half_px.max() + 4))
    # candidate pixels: the drawn runs, thickened
    idx = np.flatnonzero(keep)
    runs = np.split(np.arange(len(idx)), np.flatnonzero(np.diff(idx) > 1) + 1)
    for r_ in runs:
        if len(r_) > 1:
            cv2.polylines(mask, [np.round(q[r_] * 16 - 8).astype(np.int32)], False, 1, reach, cv2.LINE_8, 4)
    ys, xs = np.nonzero(mask)
    tree = cKDTree(q)
    acc = np.zeros(len(ys))
    for a in SUB:
        for b in SUB:
            d, i = tree.query(np.stack([xs + a, ys + b], 1))
            acc += np.where(d <= half_px[i], dark[keep][i], 0.0)
    acc /= len(SUB) ** 2
    vals = np.round(np.clip(acc, 0, 1) * 255).astype(np.uint8)
    layer[ys, xs] = np.maximum(layer[ys, xs], vals)


def poly(layer, cam, pts, width_mm, val):
    q = cam.project(pts)
    th = max(1, int(round(width_mm * cam.scale_at(pts[len(pts) // 2]))))
    cv2.polylines(layer, [np.round(q * 16 - 8).astype(np.int32)], False, val, th, cv2.LINE_AA, 4)


def render(seed, kind, medium, out, centre_off_px=0.0):
    rng = np.random.default_rng(seed)
    truth, closed = path_truth(rng, kind)
    if medium == "photo":
        ppmm = rng.uniform(200, 300) / 25.4
        cam = Cam(rng, True, ppmm, centre_off_px)
    else:
        ppmm = (600 if medium == "scan600" else 300) / 25.4
        cam = Cam(rng, False, ppmm)
    W, H = cam.size
    black = np.zeros((H, W), np.uint8)
    red = np.zeros((H, W), np.uint8)
    graph = np.zeros((H, W), np.uint8)
    for x in (-90, 90):
        for y in (-90, 90):
            fill_disc(black, cam, (x, y), 3.0, 255)
    fill_disc(black, cam, (-90, 75), 1.5, 255)
    for t in range(-75, 76, 15):
        for c in [(t, 90), (t, -90), (90, t), (-90, t)]:
            if c != (-90, 75):
                fill_disc(black, cam, c, 0.75, 255)
    # the printed reference (red): the circle or the line of the sheet
    if kind == "circle":
        a = np.linspace(0, 2 * np.pi, 3000)
        poly(red, cam, np.stack([100 * np.cos(a), 100 * np.sin(a)], 1), 0.5, 255)
    else:
        poly(red, cam, np.array([[-100.0, 0], [100.0, 0]]), 0.5, 255)
    # pencil: darkness varying along, skips
    s = arclen(truth)
    L = s[-1]
    faint = medium != "photo" and rng.random() < 0.5
    d0 = rng.uniform(0.18, 0.3) if faint else rng.uniform(0.35, 0.7)
    w0 = rng.uniform(0.3, 0.55)
    nsk = rng.integers(3, 9)
    skips = []
    for _ in range(200):
        if len(skips) == nsk:
            break
        a = rng.uniform(8, L - 14)
        b = a + rng.uniform(1, 6)
        if all(b + 3 < x or a > y + 3 for x, y in skips):
            skips.append((a, b))
    drawn = np.ones(len(s), bool)
    for a, b in skips:
        drawn &= ~((s >= a) & (s <= b))
    phase = rng.uniform(0, 6, 3)
    dark = np.minimum(d0 * (1 + 0.25 * np.sin(s / 17 + phase[0]) + 0.15 * np.sin(s / 5.3 + phase[1])), 0.95)
    width = w0 * (1 + 0.1 * np.sin(s / 9 + phase[2]))
    stroke(graph, cam, truth, drawn, dark, width)
    # grain: graphite broken up at the paper's tooth
    tooth = cv2.GaussianBlur(rng.random((H, W), np.float32), (0, 0), 0.8)
    tooth = (tooth - tooth.mean()) / (tooth.std() + 1e-6)
    g = graph.astype(np.float32) / 255 * np.clip(1 + 0.3 * tooth, 0.2, 1.6)
    # dust and fibres
    for _ in range(rng.integers(20, 60)):
        c = rng.uniform(-100, 100, 2)
        fill_disc(black, cam, c, rng.uniform(0.04, 0.15), int(rng.uniform(60, 200)))
    for _ in range(rng.integers(3, 9)):
        c = rng.uniform(-100, 100, 2); a = rng.uniform(0, np.pi); l = rng.uniform(1, 4)
        t = np.linspace(0, l, 40)
        bend = rng.uniform(-0.3, 0.3)
        pts = np.stack([c[0] + t * math.cos(a) - bend * t * t * math.sin(a), c[1] + t * math.sin(a) + bend * t * t * math.cos(a)], 1)
        poly(graph, cam, pts, 0.05, int(rng.uniform(40, 120)))
    # compose: paper x red ink x graphite x print, then light
    k = black.astype(np.float32) / 255
    rc = red.astype(np.float32) / 255
    paper = np.array([235, 232, 225], np.float32) * rng.uniform(0.9, 1.05)
    tr = np.array([0.93, 0.25, 0.22], np.float32)
    img = paper[None, None, :] * (1 - rc[..., None] * (1 - tr)) * (1 - np.clip(g, 0, 0.97)[..., None]) * (1 - 0.93 * k[..., None])
    yy, xx = np.mgrid[0:H, 0:W].astype(np.float32)
    if medium == "photo":
        gx, gy = rng.uniform(-0.25, 0.25, 2)
        light = 1 + gx * (xx / W - 0.5) + gy * (yy / H - 0.5)
        # a soft shadow over a corner
        sx, sy = rng.uniform(0, W), rng.uniform(0, H)
        a = rng.uniform(0, 2 * np.pi)
        dist = (xx - sx) * math.cos(a) + (yy - sy) * math.sin(a)
        light *= 1 - 0.25 / (1 + np.exp(-dist / (0.02 * W)))
        img = img * light[..., None]
        img = cv2.GaussianBlur(img, (0, 0), rng.uniform(0.5, 1.0))
        img += rng.normal(0, 3.0, img.shape).astype(np.float32)
    else:
        img += rng.normal(0, 1.5, img.shape).astype(np.float32)
    img = np.clip(img, 0, 255).astype(np.uint8)
    bgr = img[..., ::-1]
    if medium == "photo":
        cv2.imwrite(out, bgr, [cv2.IMWRITE_JPEG_QUALITY, int(rng.integers(85, 96))])
    else:
        cv2.imwrite(out, bgr)
    return truth, closed, skips


def score(trace, truth):
    from scipy.spatial import cKDTree
    # the trace as a polyline, densified to 0.01 mm
    seg = np.diff(trace, axis=0)
    n = np.maximum(1, np.ceil(np.hypot(*seg.T) / 0.01).astype(int))
    dense = np.concatenate([trace[i] + np.outer(np.arange(n[i]) / n[i], seg[i]) for i in range(len(seg))] + [trace[-1:]])
    t = cKDTree(dense)
    d, _ = t.query(truth)
    cov = float((d <= 0.1).mean())
    # trace to truth
    dd, _ = cKDTree(truth).query(trace)
    return cov, float(np.sqrt((dd ** 2).mean())), float(d.max())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("kind", choices=["circle", "line", "free"])
    ap.add_argument("medium", choices=["photo", "scan300", "scan600"])
    ap.add_argument("first_seed", type=int)
    ap.add_argument("count", type=int)
    ap.add_argument("--rig", default="target/release/rigctl")
    ap.add_argument("--out", default="target/tmp/trace_render3")
    ap.add_argument("--centre-off-px", type=float, default=0.0,
                    help="photos: the lens's optical centre this far (0.5-1x, random direction) from the image centre, as in a photo cropped off its centre")
    ap.add_argument("--grey", action="store_true",
                    help="turn each image to grey (luminance) before tracing, as a greyscale scanner or camera mode would: the red print as dark as the pencil")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    met = exit1 = low0 = 0
    for seed in range(args.first_seed, args.first_seed + args.count):
        ext = "jpg" if args.medium == "photo" else "png"
        image = os.path.join(args.out, f"{args.kind}_{args.medium}_{seed}.{ext}")
        truth, _, _ = render(seed, args.kind, args.medium, image, args.centre_off_px)
        if args.grey:
            grey = cv2.cvtColor(cv2.imread(image), cv2.COLOR_BGR2GRAY)
            cv2.imwrite(image, grey)
        csv_path = image[:-4] + ".csv"
        if os.path.exists(csv_path):
            os.remove(csv_path)
        run = subprocess.run([args.rig, "trace", image, "--out", csv_path], capture_output=True, text=True)
        res = {"seed": seed, "kind": args.kind, "medium": args.medium, "rc": run.returncode}
        if os.path.exists(csv_path):
            written = np.loadtxt(csv_path, delimiter=",", skiprows=1, ndmin=2)
            cov, rms, worst = score(written, truth)
            res.update(cov=round(cov, 4), rms=round(rms, 4), worst=round(worst, 2))
        err = run.stderr.strip()
        res["msg"] = err.splitlines()[-1][:200] if err else ""
        print(json.dumps(res), flush=True)
        if run.returncode == 0 and res.get("cov", 0) >= 0.95 and res.get("rms", 1) <= RMS_BAR_MM[args.medium]:
            met += 1
        if run.returncode == 0 and res.get("cov", 0) < 0.95:
            low0 += 1
        if run.returncode == 1:
            exit1 += 1
    print(json.dumps({"images": args.count, "meet_bars": met, "exit_1": exit1, "exit_0_below_0.95": low0}))


if __name__ == "__main__":
    main()
