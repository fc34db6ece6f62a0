#!/usr/bin/env python3
"""Whose scale is off: the run's path length against the truth's and against the LiDAR's own.

  PYTHONPATH=build/release/python scripts/scan_icp_scale.py DRIVE RUN [FRAMES]

DRIVE is anything `rgbl run` reads with a LiDAR (opened through the rgbl module); RUN an `rgbl run --out` folder of it (trajectory_kitti.txt, ground_truth_kitti.txt). Consecutive
scans are registered point to plane (3-40 m, 0.25 m voxels, normals from 10 neighbours, Cauchy
weights), started from the truth's step length straight ahead, so the LiDAR measures each step
without the camera, the calibration or the tracker. Prints the summed step lengths of the truth, the
run and the registration, and their ratios. Needs the Python module (build/release/python),
python3-numpy and python3-scipy.
"""
import os
import sys

import numpy as np
import rgbl
from scipy.spatial import cKDTree


def thin(scan):
    p = scan[:, :3].astype(np.float64)
    r = np.linalg.norm(p, axis=1)
    p = p[(r > 3) & (r < 40)]
    _, keep = np.unique(np.floor(p / 0.25).astype(np.int64), axis=0, return_index=True)
    return p[keep]


def register(src, dst, T):
    tree = cKDTree(dst)
    _, nn = tree.query(dst, k=10)
    q = dst[nn] - dst[nn].mean(1, keepdims=True)
    w, V = np.linalg.eigh(np.einsum('nki,nkj->nij', q, q))
    normal, flatness = V[:, :, 0], w[:, 0] / (w.sum(1) + 1e-12)
    for _ in range(30):
        s = (T[:3, :3] @ src.T).T + T[:3, 3]
        d, i = tree.query(s)
        m = (d < 0.5) & (flatness[i] < 0.05)
        s, n = s[m], normal[i[m]]
        r = ((s - dst[i[m]]) * n).sum(1)
        J = np.hstack([np.cross(s, n), n])
        wt = 1.0 / (1.0 + (r / 0.1) ** 2)
        dx = np.linalg.solve((J * wt[:, None]).T @ J, -(J * wt[:, None]).T @ r)
        a = np.linalg.norm(dx[:3])
        R = np.eye(3)
        if a > 0:
            k = dx[:3] / a
            K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
            R = np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K
        D = np.eye(4)
        D[:3, :3], D[:3, 3] = R, dx[3:]
        T = D @ T
        if np.linalg.norm(dx) < 1e-6:
            break
    return T


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    sequence = rgbl.open_sequence(argv[1], cameras=[False] * 4, depth=False)
    run = argv[2]
    gt = np.loadtxt(os.path.join(run, 'ground_truth_kitti.txt')).reshape(-1, 3, 4)
    est = np.loadtxt(os.path.join(run, 'trajectory_kitti.txt')).reshape(-1, 3, 4)
    frames = min(len(gt), len(est), len(sequence), int(argv[3]) + 1 if len(argv) > 3 else 10 ** 9)

    def scan(k):
        return thin(sequence.load(k, cameras=[False] * 4, depth=False).scan)


    def step(poses, k):
        A, B = np.eye(4), np.eye(4)
        A[:3], B[:3] = poses[k - 1], poses[k]
        return np.linalg.norm((np.linalg.inv(A) @ B)[:3, 3])

    truth, tracked, lidar = 0.0, 0.0, 0.0
    previous = scan(0)
    for k in range(1, frames):
        current = scan(k)
        g = step(gt, k)
        T0 = np.eye(4)
        T0[0, 3] = g  # the Velodyne's x points ahead
        truth += g
        tracked += step(est, k)
        lidar += np.linalg.norm(register(current, previous, T0)[:3, 3])
        previous = current
    print(f'{frames - 1} steps: truth {truth:.3f} m, run {tracked:.3f} m, LiDAR registration {lidar:.3f} m; '
          f'run / truth {tracked / truth:.4f}, LiDAR / truth {lidar / truth:.4f}, run / LiDAR {tracked / lidar:.4f}')


if __name__ == '__main__':
    main(sys.argv)
