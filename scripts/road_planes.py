#!/usr/bin/env python3
"""How far the road planes of two frames disagree under given poses: the road of frame i (a plane
fitted to the LiDAR returns below the camera, camera frame) carried into frame i+STEP by the poses,
against the road frame i+STEP sees itself. On ground-truth poses this is what local BA's road pairs
must tolerate (docs/accuracy.md, "The road ties local BA's keyframes"); on an estimate it shows steps
that leave the road.

    scripts/road_planes.py SEQUENCE_DIR POSES [STEP] [--list]

SEQUENCE_DIR in KITTI odometry layout (calib.txt with Tr, velodyne/NNNNNN.bin), e.g.
../shared/data/kitti/odometry/sequences/04; POSES in KITTI format (camera-0 poses, one row per frame:
the odometry ground truth, or trajectory_kitti.txt / ground_truth_kitti.txt of an rgbl run folder).
Prints the median and largest disagreement in height (m) and tilt (deg); --list prints every pair.
The plane here is this script's own RANSAC (every 8th return within 2-40 m, 0.1 m, 200 fixed-seed
draws, then least squares), not the tracker's. Needs python3-numpy.
"""
import os
import sys

import numpy as np


def calibration(seq):
    cal = {}
    with open(os.path.join(seq, "calib.txt")) as f:
        for line in f:
            if ":" in line:
                key, values = line.split(":", 1)
                cal[key.strip()] = np.array(values.split(), float)
    if "Tr" not in cal:
        sys.exit(f"road_planes: {seq}/calib.txt has no Tr (LiDAR to camera)")
    T = np.eye(4)
    T[:3] = cal["Tr"].reshape(3, 4)
    return T


def road(seq, T_cam_lidar, i, rng):
    path = os.path.join(seq, "velodyne", f"{i:06d}.bin")
    pts = np.fromfile(path, np.float32).reshape(-1, 4)[::8, :3].astype(float)
    r = np.linalg.norm(pts, axis=1)
    pts = pts[(r > 2.0) & (r < 40.0)]
    cam = pts @ T_cam_lidar[:3, :3].T + T_cam_lidar[:3, 3]
    cam = cam[cam[:, 1] > 0.5]  # below the camera (y down)
    if len(cam) < 50:
        return None
    best = None
    for _ in range(200):
        s = cam[rng.choice(len(cam), 3, replace=False)]
        n = np.cross(s[1] - s[0], s[2] - s[0])
        if np.linalg.norm(n) < 1e-9:
            continue
        n /= np.linalg.norm(n)
        inliers = np.abs(cam @ n - n @ s[0]) < 0.1
        if best is None or inliers.sum() > best.sum():
            best = inliers
    q = cam[best]
    mean = q.mean(axis=0)
    n = np.linalg.svd(q - mean)[2][2]
    if n[1] < 0:
        n = -n  # pointing down, as the camera's y
    return n, n @ mean  # n . x = d, d the camera's height


def main():
    args = [a for a in sys.argv[1:] if a != "--list"]
    if len(args) < 2:
        sys.exit(__doc__)
    seq, poses = args[0], args[1]
    step = int(args[2]) if len(args) > 2 else 1
    T_cam_lidar = calibration(seq)
    P = np.loadtxt(poses).reshape(-1, 3, 4)
    frames = min(len(P), len([f for f in os.listdir(os.path.join(seq, "velodyne")) if f.endswith(".bin")]))
    rng = np.random.default_rng(0)
    planes = [road(seq, T_cam_lidar, i, rng) for i in range(frames)]
    rows = []
    for i in range(step, frames, step):
        if planes[i - step] is None or planes[i] is None:
            continue
        T0, T1 = np.eye(4), np.eye(4)
        T0[:3], T1[:3] = P[i - step], P[i]
        T01 = np.linalg.inv(T0) @ T1  # frame i -> frame i - step
        (n0, d0), (n1, d1) = planes[i - step], planes[i]
        height = (d0 - n0 @ T01[:3, 3]) - d1  # the camera's height over the old road, against over its own
        tilt = np.degrees(np.arccos(np.clip(n0 @ (T01[:3, :3] @ n1), -1.0, 1.0)))
        rows.append((i, height, tilt))
    if not rows:
        sys.exit("road_planes: no pair of frames with a road in both scans")
    rows = np.array(rows)
    print(f"{len(rows)} pairs {step} frame(s) apart: height median {np.median(np.abs(rows[:, 1])):.3f} m, "
          f"largest {np.abs(rows[:, 1]).max():.3f} m; tilt median {np.median(rows[:, 2]):.2f} deg, "
          f"largest {rows[:, 2].max():.2f} deg")
    if "--list" in sys.argv:
        for i, h, t in rows:
            print(f"{int(i)} {h:+.3f} m {t:.2f} deg")


if __name__ == "__main__":
    main()
