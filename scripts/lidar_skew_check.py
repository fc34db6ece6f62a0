#!/usr/bin/env python3
"""Is a drive's LiDAR motion-compensated, and which way does it spin? (python3-numpy, -scipy, -opencv)

  scripts/lidar_skew_check.py raw|odometry DRIVE_OR_SEQUENCE_DIR FRAMES [SPIN GROUND_TRUTH_KITTI]

Compares LiDAR depth with stereo (SGBM) depth at the LiDAR points' pixels, binned by LiDAR azimuth.
Stereo is exposed at one instant; a spinning LiDAR that is not compensated measures one side of the
image before the other, so the difference grows linearly with azimuth (slope ~ speed / spin rate).
With SPIN (+1: clockwise from above, -1) and a ground-truth trajectory (trajectory file of `rgbl run`'s
ground_truth_kitti.txt) each point is first moved to the camera time with the true velocity, as
a motion correction of the sweep would do (docs/accuracy.md, "The LiDAR's sweep"): the right sign flattens the trend.
"""
import glob
import sys

import cv2
import numpy as np
from scipy.linalg import expm, logm

kind, root, frames = sys.argv[1], sys.argv[2], int(sys.argv[3])
spin = float(sys.argv[4]) if len(sys.argv) > 5 else 0.0


def h(P):
    M = np.eye(4)
    M[:3] = P
    return M


if kind == "odometry":
    cal = {l.split(":")[0]: np.array(l.split()[1:], float) for l in open(root + "/calib.txt") if ":" in l}
    P0, P1, T = cal["P0"].reshape(3, 4), cal["P1"].reshape(3, 4), h(cal["Tr"].reshape(3, 4))
    left, right = sorted(glob.glob(root + "/image_0/*.png")), sorted(glob.glob(root + "/image_1/*.png"))
    scans = sorted(glob.glob(root + "/velodyne/*.bin"))
else:
    day = root.rstrip("/").rsplit("/", 1)[0]
    read = lambda f: {k: v for k, _, v in (l.partition(":") for l in open(f))}
    c, v = read(day + "/calib_cam_to_cam.txt"), read(day + "/calib_velo_to_cam.txt")
    P0, P1 = (np.array(c[k].split(), float).reshape(3, 4) for k in ("P_rect_00", "P_rect_01"))
    R_rect = np.eye(4)
    R_rect[:3, :3] = np.array(c["R_rect_00"].split(), float).reshape(3, 3)
    T = np.eye(4)
    T[:3, :3] = np.array(v["R"].split(), float).reshape(3, 3)
    T[:3, 3] = np.array(v["T"].split(), float)
    T = R_rect @ T
    left, right = sorted(glob.glob(root + "/image_00/data/*.png")), sorted(glob.glob(root + "/image_01/data/*.png"))
    scans = sorted(glob.glob(root + "/velodyne_points/data/*.bin"))
gt = [h(g) for g in np.loadtxt(sys.argv[5]).reshape(-1, 3, 4)] if spin else None
f = P0[0, 0]
baseline = -(P1[0, 3] - P0[0, 3]) / f
sgbm = cv2.StereoSGBM_create(minDisparity=0, numDisparities=128, blockSize=5, P1=200, P2=800, uniquenessRatio=15,
                             speckleWindowSize=100, speckleRange=1, mode=cv2.STEREO_SGBM_MODE_HH)
azimuths, residuals = [], []
for i in range(min(frames, len(left))):
    disp = sgbm.compute(cv2.imread(left[i], 0), cv2.imread(right[i], 0)).astype(np.float32) / 16.0
    p = np.fromfile(scans[i], np.float32).reshape(-1, 4)[:, :3].astype(float)
    p = p[p[:, 0] > 2]
    az = np.arctan2(p[:, 1], p[:, 0])
    pc = (T[:3, :3] @ p.T).T + T[:3, 3]
    if spin:
        j = min(i, len(gt) - 2) + 1
        xi = logm(np.linalg.inv(gt[j]) @ gt[j - 1]).real  # T_cur_last, per frame (= per sweep)
        frac = np.round(spin * az / (2 * np.pi), 4)  # sweeps before the camera trigger
        for b in np.unique(frac):
            E = expm(b * xi)
            pc[frac == b] = (E[:3, :3] @ pc[frac == b].T).T + E[:3, 3]
    uvw = (P0 @ np.c_[pc, np.ones(len(pc))].T).T
    z = uvw[:, 2]
    u, v = uvw[:, 0] / z, uvw[:, 1] / z
    ok = (z > 5) & (z < 20) & (u >= 0) & (u < disp.shape[1] - 1) & (v >= 0) & (v < disp.shape[0] - 1)
    d = disp[np.round(v[ok]).astype(int), np.round(u[ok]).astype(int)]
    good = d > 5
    r = z[ok][good] - f * baseline / d[good]
    keep = np.abs(r) < 0.05 * z[ok][good]  # edges and mismatches
    azimuths.append(az[ok][good][keep])
    residuals.append(r[keep])
A, R = np.degrees(np.concatenate(azimuths)), np.concatenate(residuals)
print(f"{kind}, spin correction {spin:+.0f}: {len(A)} points")
for lo in range(-40, 40, 10):
    s = (A >= lo) & (A < lo + 10)
    if s.sum() > 50:
        print(f"  azimuth {lo:+3d}..{lo + 10:+3d} deg: median LiDAR - stereo depth {100 * np.median(R[s]):+5.1f} cm ({s.sum()} points)")
print(f"  left (> 10 deg) - right (< -10 deg): {100 * (np.median(R[A > 10]) - np.median(R[A < -10])):+.1f} cm")
