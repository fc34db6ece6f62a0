#!/usr/bin/env python3
"""Does a real drive's vegetation read deep in the LiDAR? The library's `lidar` source at ORB keypoints
of camera 0 against its `stereo_sparse` source (ORB-SLAM's row search with camera 1: SAD window,
uniqueness test, parabola sub-pixel; include/rgbl/depth/sources.hpp) at the same pixels, split by
distance and by colour: a keypoint is green where camera 2's image at its stereo point has excess
green (2g - r - b) / (r + g + b) above 0.06 (docs/accuracy.md, "Seeds never looked at", real vegetation).

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
camera = cal.camera(0)
P2 = np.asarray(cal.P[2])
lidar = rgbl.make_lidar_source(camera, surface_fit_window_deg=fit)
stereo = rgbl.make_depth_source('stereo_sparse', camera, stereo_baseline=cal.baseline(0, 1))
orb = cv2.ORB_create(2000)
rows = []  # lidar z, stereo z, excess green
for i in range(0, len(seq), step):
    fr = seq.load(i)
    left, right, colour = fr.images[0], fr.images[1], fr.images[2]
    if left.ndim == 3: left = cv2.cvtColor(left, cv2.COLOR_BGR2GRAY)
    if right.ndim == 3: right = cv2.cvtColor(right, cv2.COLOR_BGR2GRAY)
    pixels = np.array([k.pt for k in orb.detect(left, None)], np.float32).reshape(-1, 2)
    lidar.prepare(left, fr.scan)
    stereo.prepare(left, image_right=right)
    for (u, v), (zl, _, spread, _), (zs, _, _, _) in zip(pixels, np.asarray(lidar.sample(pixels)),
                                                         np.asarray(stereo.sample(pixels))):
        if not (3.0 < zl < 40.0) or spread > max(1.0, 0.05 * zl) or not zs > 0:
            continue
        # the colour of the stereo point in camera 2
        X = np.array([*camera.camera.unproject((float(u), float(v)), float(zs)), 1.0])
        u2 = P2 @ X
        x2, y2 = int(round(u2[0] / u2[2])), int(round(u2[1] / u2[2]))
        if not (2 <= x2 < colour.shape[1] - 2 and 2 <= y2 < colour.shape[0] - 2):
            continue
        bgr = colour[y2 - 2:y2 + 3, x2 - 2:x2 + 3].reshape(-1, 3).astype(float).mean(0)
        rows.append((zl, zs, (2 * bgr[1] - bgr[2] - bgr[0]) / (bgr.sum() + 1e-6)))
rows = np.array(rows)
rel = rows[:, 0] / rows[:, 1] - 1
print(f'{seq_path}: {len(rows)} keypoints with both depths, fit {fit}')


def show(name, m):
    if m.sum() < 10:
        print(f'  {name:34s} n={m.sum()}')
        return
    r = rel[m]
    print(f'  {name:34s} n={m.sum():5d} median {100 * np.median(r):+6.2f} %  mean {100 * np.mean(np.clip(r, -0.3, 0.3)):+6.2f} %'
          f'  >2% far {100 * np.mean(r > 0.02):4.1f} %  >2% near {100 * np.mean(r < -0.02):4.1f} %')


green = rows[:, 2] > 0.06
show('all', np.ones(len(rows), bool))
for lo, hi in ((3, 8), (8, 15), (15, 40)):
    d = (rows[:, 1] >= lo) & (rows[:, 1] < hi)
    show(f'{lo}-{hi} m green (ExG>0.06)', d & green)
    show(f'{lo}-{hi} m other', d & ~green)
