#!/usr/bin/env python3
"""A copy of a KITTI drive whose scans are moved to the images' time, outside rgbl (docs/accuracy.md,
"The LiDAR's sweep"): each return measured DELTA seconds before its image (plus, with SPIN, the sweep:
SPIN * azimuth / 2 pi * 0.1 s; +1 = clockwise from above, -1 = the other way) is moved by the camera's
motion over that time, from the ground truth's steps (first order). The images, times and calibration
are linked, not copied. Used to check what rgbl's LiDAR.TimeOffset does, and to try the sweep.

  rgbl -q run $RX --out /tmp/rx     # its ground_truth_kitti.txt gives the motion
  scripts/scan_time_shift.py raw $RX /tmp/rx/ground_truth_kitti.txt 0.0169 /tmp/rx-shift 1
  rgbl -q run /tmp/rx-shift/2011_09_26/2011_09_26_drive_0009_sync --config t0.yaml   # LiDAR.TimeOffset: 0

kind raw: SRC = <date>/<drive>_sync; odo: SRC = sequences/NN (poses/ is linked beside it).
Needs python3-numpy and python3-opencv.
"""
import os
import sys

import cv2
import numpy as np

kind, src, gt, delta, out = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4]), sys.argv[5]
spin = float(sys.argv[6]) if len(sys.argv) > 6 else 0.0  # -1: azimuth grows with time (KITTI file order)
P = [np.vstack([np.array(l.split(), float).reshape(3, 4), [0, 0, 0, 1]]) for l in open(gt) if l.strip()]
def kv(path):
    d = {}
    for l in open(path):
        if ':' in l:
            k, r = l.split(':', 1)
            try: d[k.strip()] = np.array([float(x) for x in r.split()])
            except ValueError: pass
    return d
def times(path):
    t = []
    for l in open(path):
        l = l.strip()
        if not l: continue
        if ' ' in l:
            h, m, s = l.split(' ')[1].split(':'); t.append(int(h) * 3600 + int(m) * 60 + float(s))
        else: t.append(float(l))
    return np.array(t)
if kind == 'raw':
    day = os.path.dirname(os.path.abspath(src)); name = os.path.basename(os.path.abspath(src))
    c = kv(os.path.join(day, 'calib_velo_to_cam.txt')); cc = kv(os.path.join(day, 'calib_cam_to_cam.txt'))
    T = np.eye(4); T[:3, :3] = c['R'].reshape(3, 3); T[:3, 3] = c['T']
    R0 = np.eye(4); R0[:3, :3] = cc['R_rect_00'].reshape(3, 3)
    T_cam_velo = R0 @ T
    odir = os.path.join(out, os.path.basename(day)); os.makedirs(os.path.join(odir, name, 'velodyne_points', 'data'), exist_ok=True)
    for f in os.listdir(day):
        if f.endswith('.txt') and not os.path.exists(os.path.join(odir, f)): os.symlink(os.path.join(day, f), os.path.join(odir, f))
    for sub in os.listdir(src):
        if sub != 'velodyne_points' and not os.path.exists(os.path.join(odir, name, sub)): os.symlink(os.path.join(os.path.abspath(src), sub), os.path.join(odir, name, sub))
    for f in os.listdir(os.path.join(src, 'velodyne_points')):
        if f.endswith('.txt') and not os.path.exists(os.path.join(odir, name, 'velodyne_points', f)): os.symlink(os.path.abspath(os.path.join(src, 'velodyne_points', f)), os.path.join(odir, name, 'velodyne_points', f))
    t = times(os.path.join(src, 'image_00', 'timestamps.txt'))
    scans = sorted(os.listdir(os.path.join(src, 'velodyne_points', 'data')))
    sdir = os.path.join(src, 'velodyne_points', 'data'); odata = os.path.join(odir, name, 'velodyne_points', 'data')
else:
    c = kv(os.path.join(src, 'calib.txt'))
    T_cam_velo = np.vstack([c['Tr'].reshape(3, 4), [0, 0, 0, 1]])
    seq = os.path.basename(os.path.abspath(src)); odir = os.path.join(out, 'sequences', seq)
    os.makedirs(os.path.join(odir, 'velodyne'), exist_ok=True)
    for sub in os.listdir(src):
        if sub != 'velodyne' and not os.path.exists(os.path.join(odir, sub)): os.symlink(os.path.join(os.path.abspath(src), sub), os.path.join(odir, sub))
    poses = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(src))), 'poses')
    if not os.path.exists(os.path.join(out, 'poses')): os.symlink(poses, os.path.join(out, 'poses'))
    t = times(os.path.join(src, 'times.txt'))
    sdir = os.path.join(src, 'velodyne'); scans = sorted(os.listdir(sdir)); odata = os.path.join(odir, 'velodyne')
inv = np.linalg.inv(T_cam_velo)
for i, s in enumerate(scans):
    a, b = (i - 1, i) if i > 0 else (0, 1)
    Trel = np.linalg.inv(P[a]) @ P[b]
    rv, _ = cv2.Rodrigues(Trel[:3, :3]); rv = rv.ravel(); tr = Trel[:3, 3]; dt = t[b] - t[a]
    pts = np.fromfile(os.path.join(sdir, s), np.float32).reshape(-1, 4).copy()
    az = np.arctan2(pts[:, 1], pts[:, 0]).astype(np.float64)
    f = (delta + spin * az / (2 * np.pi) * 0.1) / dt  # frames the point is measured before the camera
    pc = pts[:, :3].astype(np.float64) @ T_cam_velo[:3, :3].T + T_cam_velo[:3, 3]
    # p_tc = Td^-1 p_tl with Td = (I + [f rv]x, f tr): first order in the rotation
    q = pc - f[:, None] * tr[None, :]
    q = q - np.cross(f[:, None] * rv[None, :], q)
    pts[:, :3] = (q @ inv[:3, :3].T + inv[:3, 3]).astype(np.float32)
    pts.tofile(os.path.join(odata, s))
