#!/usr/bin/env python3
"""Heading checks of one `rgbl run` output folder (trajectory_kitti.txt, ground_truth_kitti.txt).

  scripts/heading_consistency.py OUT_DIR        (needs python3-numpy)

Prints how far the estimated heading is from the ground truth's, how far the ground truth's own steps
point from its own heading (a car drives where it points: ~0 on a consistent truth), and the end-point
error split into the first camera's x (sideways), y (down) and z (forward) axes, and the estimated
path's length over the truth's (a scale error shows as a ratio off 1), and the end-point error as
is and with the estimate turned by the truth's own step-direction offset.
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
# The same end-point drift with the truth's heading taken from its own track: turn the estimate about
# the first camera's vertical axis by the truth's mean step-direction offset (a figure of the truth
# alone, not fitted to the estimate). A truth whose heading disagrees with its positions shows here.
a = np.radians(off.mean())
R = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])
turned = (R @ (est[:, :, 3] - est[0, :, 3]).T).T + gt[0, :, 3]
for name, p in (("as is", est[:, :, 3] - est[0, :, 3] + gt[0, :, 3]), (f"turned by {off.mean():.2f} deg", turned)):
    print(f"end-point error {name}: {np.linalg.norm(p[-1] - gt[-1, :, 3]):.3f} m = "
          f"{100 * np.linalg.norm(p[-1] - gt[-1, :, 3]) / length(gt):.2f} % of the truth's path")
