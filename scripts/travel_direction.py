#!/usr/bin/env python3
"""How far a trajectory's steps leave its mean direction of travel, in the camera's frame.

    scripts/travel_direction.py <KITTI poses file or run folder> ...   (a run folder: its ground_truth_kitti.txt)

A car's camera moves along the car's direction of travel, fixed in the camera's frame by the mount.
For each step of at least 0.2 m, the step is read in the camera frame turned half-way between the two
frames' orientations (as rgbl's TravelDirection reads it); the mean of those unit steps is the
direction. Prints the direction, the median step, and how far the steps leave it across (RMS and
largest, in metres and as a share of the step) and the median turn per frame: the figures the
tracker's direction prior (TrackerOptions::direction_prior) is checked against, docs/accuracy.md.
Needs python3-numpy.
"""
import pathlib
import sys

import numpy as np


def load(path):
    p = pathlib.Path(path)
    if p.is_dir():
        p = p / "ground_truth_kitti.txt"
    rows = np.loadtxt(p).reshape(-1, 3, 4)
    T = np.tile(np.eye(4), (len(rows), 1, 1))
    T[:, :3, :] = rows
    return T  # T_world_cam


def so3_log(R):
    c = np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arccos(c)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return 0.5 * w if angle < 1e-9 else angle / (2.0 * np.sin(angle)) * w


def so3_exp(phi):
    angle = np.linalg.norm(phi)
    if angle < 1e-12:
        return np.eye(3)
    k = phi / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * K @ K


def main(paths):
    if not paths:
        print(__doc__)
        return 2
    for path in paths:
        T = load(path)
        steps, turns = [], []
        for i in range(1, len(T)):
            R_last, R_cur = T[i - 1, :3, :3], T[i, :3, :3]
            phi = so3_log(R_last.T @ R_cur)  # in the last camera's frame
            R_mid = R_last @ so3_exp(0.5 * phi)
            steps.append(R_mid.T @ (T[i, :3, 3] - T[i - 1, :3, 3]))
            turns.append(np.linalg.norm(phi))
        S = np.array(steps)
        L = np.linalg.norm(S, axis=1)
        m = L >= 0.2
        if m.sum() < 3:
            print(f"{path}: fewer than 3 steps of 0.2 m or more")
            continue
        mean = (S[m] / L[m, None]).mean(axis=0)
        mean /= np.linalg.norm(mean)
        across = np.linalg.norm(S[m] - np.outer(S[m] @ mean, mean), axis=1)
        print(f"{path}: {m.sum()} steps, direction {np.round(mean, 4)}, median step {np.median(L[m]):.2f} m, across "
              f"RMS {np.sqrt((across ** 2).mean()):.4f} m ({100 * np.sqrt(((across / L[m]) ** 2).mean()):.2f} % of "
              f"the step), largest {across.max():.4f} m, median turn {np.median(turns):.4f} rad")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
