#!/usr/bin/env python3
"""Frame-to-frame pose error by axis, in the camera frame: where a trajectory's jitter and bias are.

    scripts/rpe_axes.py <run folder of rgbl run / rgbl demo>   (trajectory_kitti.txt, ground_truth_kitti.txt)
    scripts/rpe_axes.py <estimate.txt> <ground_truth.txt>      (KITTI format, row for row)

For each pair of consecutive frames, E = (T_gt_i^-1 T_gt_i+1)^-1 (T_est_i^-1 T_est_i+1); prints the mean
(bias) and RMS (jitter) of E's rotation about x (pitch), y (yaw), z (roll) in degrees and of its
translation in metres (x right, y down, z forward); then the five steps with the largest translation
error, and the ATE by axis after a rigid (SE(3)) alignment, in the first frame's axes (and the ATE
after a similarity alignment, with its scale), and the path's length against the truth's, in all and
per 20 frames. Given a run
folder with timing.csv, also the same rotation error between consecutive keyframes (the frames made
keyframes, at their written poses). Needs python3-numpy.
"""
import csv
import pathlib
import sys

import numpy as np


def load(path):
    rows = np.loadtxt(path, ndmin=2)
    poses = np.tile(np.eye(4), (len(rows), 1, 1))
    poses[:, :3, :] = rows[:, -12:].reshape(-1, 3, 4)
    return poses


def rotation_vector(R):
    angle = np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))
    if angle < 1e-12:
        return np.zeros(3)
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return angle / (2.0 * np.sin(angle)) * axis


def step_errors(est, gt, pairs):
    """Rotation (deg) and translation (m) error of the motion i -> j for each pair (i, j)."""
    rot, trans = [], []
    for i, j in pairs:
        E = np.linalg.inv(np.linalg.inv(gt[i]) @ gt[j]) @ (np.linalg.inv(est[i]) @ est[j])
        rot.append(np.degrees(rotation_vector(E[:3, :3])))
        trans.append(E[:3, 3])
    return np.array(rot), np.array(trans)


def main():
    keyframes = []
    if len(sys.argv) == 2:
        run = pathlib.Path(sys.argv[1])
        estimate, truth = run / "trajectory_kitti.txt", run / "ground_truth_kitti.txt"
        if (run / "timing.csv").exists():
            with open(run / "timing.csv", newline="") as f:
                keyframes = [int(r["frame"]) for r in csv.DictReader(f) if r["keyframe"] == "1"]
    elif len(sys.argv) == 3:
        estimate, truth = sys.argv[1], sys.argv[2]
    else:
        sys.exit(__doc__)
    est, gt = load(estimate), load(truth)
    n = min(len(est), len(gt))
    if n < 2:
        sys.exit("error: fewer than 2 poses to compare")
    rot, trans = step_errors(est, gt, [(i, i + 1) for i in range(n - 1)])
    print(f"{n} frames")
    print("rotation deg     pitch(x)  yaw(y)   roll(z)")
    print("  mean (bias)   " + "".join(f"{v:9.4f}" for v in rot.mean(axis=0)))
    print("  rms (jitter)  " + "".join(f"{v:9.4f}" for v in np.sqrt((rot ** 2).mean(axis=0))))
    keyframes = [k for k in keyframes if k < n]
    if len(keyframes) >= 2:
        kf_rot, _ = step_errors(est, gt, list(zip(keyframes[:-1], keyframes[1:])))
        print("  rms keyframes " + "".join(f"{v:9.4f}" for v in np.sqrt((kf_rot ** 2).mean(axis=0)))
              + f"   (between {len(keyframes)} consecutive keyframes)")
    print("translation m    x        y(down)  z(fwd)")
    print("  mean (bias)   " + "".join(f"{v:9.4f}" for v in trans.mean(axis=0)))
    print("  rms (jitter)  " + "".join(f"{v:9.4f}" for v in np.sqrt((trans ** 2).mean(axis=0))))
    print("largest steps   x        y(down)  z(fwd)   (frame i-1 -> i)")
    for i in np.argsort(-np.linalg.norm(trans, axis=1))[:5]:
        print(f"  frame {i + 1:5d}  " + "".join(f"{v:9.4f}" for v in trans[i]))
    # ATE: the estimated positions rigidly aligned to the true ones (Kabsch/Umeyama without scale)
    p_est, p_gt = est[:n, :3, 3], gt[:n, :3, 3]
    mu_est, mu_gt = p_est.mean(axis=0), p_gt.mean(axis=0)
    U, S, Vt = np.linalg.svd((p_est - mu_est).T @ (p_gt - mu_gt))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    err = (p_est - mu_est) @ R.T + mu_gt - p_gt
    print("ATE m (aligned)  x        y        z")
    print("  rms           " + "".join(f"{v:9.4f}" for v in np.sqrt((err ** 2).mean(axis=0)))
          + f"   (all {np.sqrt((err ** 2).sum(axis=1).mean()):.4f})")
    # the same with a scale (similarity alignment): how much of the ATE is a scale error
    scale = (S * np.diag(D)).sum() / ((p_est - mu_est) ** 2).sum()
    err = scale * (p_est - mu_est) @ R.T + mu_gt - p_gt
    print(f"  with a scale {scale:.4f}: {np.sqrt((err ** 2).sum(axis=1).mean()):.4f}")
    # the path's length against the truth's, in all and per 20 steps: where a scale error is made
    step_est = np.linalg.norm(np.diff(p_est, axis=0), axis=1)
    step_gt = np.linalg.norm(np.diff(p_gt, axis=0), axis=1)
    print(f"path / truth {step_est.sum() / step_gt.sum():.4f}; per 20 frames: " + ", ".join(
        f"{a}-{min(a + 20, n - 1)} {100 * (step_est[a:a + 20].sum() / step_gt[a:a + 20].sum() - 1):+.2f} %"
        for a in range(0, n - 1, 20)))


if __name__ == "__main__":
    main()
