#!/usr/bin/env python3
"""Heading checks of one `rgbl run` output folder (trajectory_kitti.txt, ground_truth_kitti.txt).

  scripts/heading_consistency.py OUT_DIR        (needs python3-numpy)

Prints how far the estimated heading is from the ground truth's, how far the ground truth's own steps
point from its own heading (a car drives where it points: ~0 on a consistent truth), and the end-point
error split into the first camera's x (sideways), y (down) and z (forward) axes, and the estimated
path's length over the truth's (a scale error shows as a ratio off 1).
"""
import sys

import numpy as np


def heading(R):  # camera forward (z) in the first camera's x-z plane, degrees
    return np.degrees(np.arctan2(R[0, 2], R[2, 2]))


out = sys.argv[1]
est = np.loadtxt(f"{out}/trajectory_kitti.txt").reshape(-1, 3, 4)
gt = np.loadtxt(f"{out}/ground_truth_kitti.txt").reshape(-1, 3, 4)
dy = np.array([heading(e[:, :3]) - heading(g[:, :3]) for e, g in zip(est, gt)])
print(f"heading estimate - truth: max |.| {np.abs(dy).max():.2f} deg, at the end {dy[-1]:.2f} deg")
off = []
for i in range(1, len(gt)):
    step = gt[i, :, 3] - gt[i - 1, :, 3]
    off.append(np.degrees(np.arctan2(step[0], step[2])) - 0.5 * (heading(gt[i, :, :3]) + heading(gt[i - 1, :, :3])))
off = np.array(off)
print(f"truth's step direction - truth's heading: mean {off.mean():.2f} deg, max |.| {np.abs(off).max():.2f} deg")
print("end-point error x (sideways), y, z (forward): " + " ".join(f"{v:.3f}" for v in est[-1, :, 3] - gt[-1, :, 3]) + " m")
length = lambda poses: np.linalg.norm(np.diff(poses[:, :, 3], axis=0), axis=1).sum()
print(f"path length estimate / truth: {length(est) / length(gt):.4f}")
