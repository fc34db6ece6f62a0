#!/usr/bin/env python3
"""Does a real drive's vegetation read deep in the LiDAR? The library's `lidar` source at ORB keypoints
of camera 0 against stereo block matching with camera 1 (9x9 ZNCC >= 0.9 along the row within 0.7-1.4x
of the LiDAR's disparity, unique by 0.05, parabola sub-pixel), split by distance and by colour: a
keypoint is green where camera 2's image at its stereo point has excess green (2g - r - b) / (r + g + b)
above 0.06 (docs/accuracy.md, "Seeds never looked at", real vegetation).

  PYTHONPATH=build/release/python scripts/stereo_vs_lidar.py SEQ [STEP] [FIT_DEG]

SEQ: a KITTI sequence or raw drive with cameras 0, 1 and 2 and a LiDAR (sequence 04, raw 0009; not
raw_extended, which holds camera 0 only); every STEP-th frame (default 2); FIT_DEG the ring plane fit
(default 0.5, the library's default). Needs python3-numpy, python3-opencv and the Python module.
"""
import sys
import cv2
import numpy as np
import rgbl

seq_path = sys.argv[1]
step = int(sys.argv[2]) if len(sys.argv) > 2 else 2
fit = float(sys.argv[3]) if len(sys.argv) > 3 else 0.5
seq = rgbl.open_sequence(seq_path)
cal = seq.calibration
P0 = np.asarray(cal.P[0]); P1 = np.asarray(cal.P[1]); P2 = np.asarray(cal.P[2])
f = P0[0, 0]; cx = P0[0, 2]; cy = P0[1, 2]
fb = -(P1[0, 3] - P0[0, 3])
src = rgbl.make_lidar_source(cal.camera(0), surface_fit_window_deg=fit)
orb = cv2.ORB_create(2000)
H = 4  # half patch
rows = []
for i in range(0, len(seq), step):
    fr = seq.load(i)
    L, R, C = fr.images[0], fr.images[1], fr.images[2]
    if L.ndim == 3: L = cv2.cvtColor(L, cv2.COLOR_BGR2GRAY)
    if R.ndim == 3: R = cv2.cvtColor(R, cv2.COLOR_BGR2GRAY)
    kps = orb.detect(L, None)
    pix = np.array([[np.floor(k.pt[0] + 0.5), np.floor(k.pt[1] + 0.5)] for k in kps], np.float32)
    src.prepare(L, fr.scan)
    s = np.asarray(src.sample(pix))
    Lf = L.astype(np.float32); Rf = R.astype(np.float32)
    h, w = L.shape
    for (x, y), (dl, dist, spread, grad) in zip(pix.astype(int), s):
        if not (3.0 < dl < 40.0) or y < H or y >= h - H or x < H + 1 or x >= w - H:
            continue
        d0 = fb / dl
        lo = max(1, int(np.floor(min(0.7 * d0, d0 - 3)))); hi = int(np.ceil(max(1.4 * d0, d0 + 3)))
        if x - hi - H < 0:
            continue
        a = Lf[y - H:y + H + 1, x - H:x + H + 1].ravel(); a = a - a.mean(); na = np.linalg.norm(a)
        if na < 1e-3 * a.size or a.std() < 4:
            continue
        strip = Rf[y - H:y + H + 1, x - hi - H:x - lo + H + 1]
        scores = []
        for d in range(lo, hi + 1):
            c0 = x - d - (x - hi - H) - H
            b = strip[:, c0:c0 + 2 * H + 1].ravel(); b = b - b.mean(); nb = np.linalg.norm(b)
            scores.append(a @ b / (na * nb + 1e-9))
        scores = np.array(scores); k = int(np.argmax(scores))
        if k == 0 or k == len(scores) - 1 or scores[k] < 0.9:
            continue
        mask = np.abs(np.arange(len(scores)) - k) > 2
        if mask.any() and scores[mask].max() > scores[k] - 0.05:
            continue
        sm, s0, sp = scores[k - 1], scores[k], scores[k + 1]
        den = sm - 2 * s0 + sp
        sub = 0.5 * (sm - sp) / den if den < 0 else 0.0
        disp = lo + k + sub
        ds = fb / disp
        # colour of the point in camera 2
        X = np.array([(x - cx) * ds / f, (y - cy) * ds / f, ds, 1.0])
        u2 = P2 @ X; u2 = u2[:2] / u2[2]
        xi, yi = int(round(u2[0])), int(round(u2[1]))
        if not (2 <= xi < C.shape[1] - 2 and 2 <= yi < C.shape[0] - 2):
            continue
        bgr = C[yi - 2:yi + 3, xi - 2:xi + 3].reshape(-1, 3).astype(float).mean(0)
        ssum = bgr.sum() + 1e-6
        exg = (2 * bgr[1] - bgr[2] - bgr[0]) / ssum
        rows.append((i, x, y, dl, ds, spread, exg, s0))
rows = np.array(rows)
rel = rows[:, 3] / rows[:, 4] - 1
print(f'{seq_path}: {len(rows)} keypoints with both depths, fit {fit}')
def show(name, m):
    if m.sum() < 10: print(f'  {name:34s} n={m.sum()}'); return
    r = rel[m]
    print(f'  {name:34s} n={m.sum():5d} median {100*np.median(r):+6.2f} %  mean {100*np.mean(np.clip(r,-0.3,0.3)):+6.2f} %  >2% far {100*np.mean(r>0.02):4.1f} %  >2% near {100*np.mean(r<-0.02):4.1f} %')
veg = rows[:, 6] > 0.06
show('all', np.ones(len(rows), bool))
for lo, hi in ((3, 8), (8, 15), (15, 40)):
    d = (rows[:, 4] >= lo) & (rows[:, 4] < hi)
    show(f'{lo}-{hi} m green (ExG>0.06)', d & veg)
    show(f'{lo}-{hi} m other', d & ~veg)
