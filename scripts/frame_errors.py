#!/usr/bin/env python3
"""Per-frame rotation error of a run against the truth, split at keyframes, and what frame-to-frame
PnP reaches on the same frames (docs/loop-closing.md, "Where the attitude error comes from").

    scripts/frame_errors.py run RUN_DIR POSES     # rgbl run's output folder, the KITTI poses file
    scripts/frame_errors.py pnp DATASET [STEP]    # a `rgbl demo --depth precomputed --keep` dataset

`run`: the rotation of each frame-to-frame step against the true step (median over all steps, over
the steps into a keyframe and over the others; timing.csv says which frames are keyframes), and the
mean local-map inliers on keyframes and on the frame after each. `pnp`: OpenCV's ORB matched between
frames STEP apart (default 1), lifted with the exact depth image, solvePnPRansac + LM refinement, the
median rotation error against the truth, with a 1-level and an 8-level pyramid. Needs python3-numpy
(and python3-opencv for pnp).
"""
import csv
import math
import sys
from pathlib import Path

import numpy as np


def poses(path):
    rows = np.loadtxt(path).reshape(-1, 3, 4)
    T = np.tile(np.eye(4), (len(rows), 1, 1))
    T[:, :3, :] = rows
    return T


def angle_deg(E):
    return math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(E[:3, :3]) - 1.0) / 2.0))))


def step_error(est, gt, i, j):
    return angle_deg(np.linalg.inv(np.linalg.inv(gt[i]) @ gt[j]) @ (np.linalg.inv(est[i]) @ est[j]))


def run(run_dir, poses_file):
    est, gt = poses(Path(run_dir) / "trajectory_kitti.txt"), poses(poses_file)
    rows = list(csv.DictReader(open(Path(run_dir) / "timing.csv")))
    keyframe = [r["keyframe"] == "1" for r in rows]
    inliers = [int(r["inliers"]) for r in rows]
    n = min(len(est), len(gt), len(rows))
    errors = [step_error(est, gt, i, i + 1) for i in range(n - 1)]
    into = [e for i, e in enumerate(errors) if keyframe[i + 1]]
    other = [e for i, e in enumerate(errors) if not keyframe[i + 1]]
    print(f"rotation error per frame step, median: {np.median(errors):.3f} deg over {len(errors)} steps; "
          f"into a keyframe {np.median(into):.3f} deg ({len(into)}), the others {np.median(other):.3f} deg")
    on = [inliers[i] for i in range(1, n) if keyframe[i]]
    after = [inliers[i + 1] for i in range(1, n - 1) if keyframe[i]]
    print(f"local-map inliers: {np.mean(on):.0f} on keyframes (mean), {np.mean(after):.0f} on the frame after")


def pnp(dataset, step):
    import cv2

    seq = Path(dataset) / "sequences" / "00"
    gt = poses(Path(dataset) / "poses" / "00.txt")
    P = np.loadtxt(seq / "calib.txt", usecols=range(1, 13), max_rows=1).reshape(3, 4)
    K = P[:, :3]
    matcher = cv2.BFMatcher(cv2.NORM_HAMMING, crossCheck=True)
    for levels in (1, 8):
        orb = cv2.ORB_create(2000, nlevels=levels, fastThreshold=10)
        errors = []
        for i in range(0, len(gt) - step):
            a = cv2.imread(str(seq / "image_0" / f"{i:06d}.png"), cv2.IMREAD_GRAYSCALE)
            b = cv2.imread(str(seq / "image_0" / f"{i + step:06d}.png"), cv2.IMREAD_GRAYSCALE)
            depth = cv2.imread(str(seq / "depth" / f"{i:06d}.png"), cv2.IMREAD_ANYDEPTH).astype(np.float64) / 256.0
            ka, da = orb.detectAndCompute(a, None)
            kb, db = orb.detectAndCompute(b, None)
            world, image = [], []
            for m in matcher.match(da, db):
                u, v = ka[m.queryIdx].pt
                z = depth[int(round(v)), int(round(u))]
                if z > 0:
                    world.append([(u - K[0, 2]) / K[0, 0] * z, (v - K[1, 2]) / K[1, 1] * z, z])
                    image.append(kb[m.trainIdx].pt)
            world, image = np.array(world), np.array(image)
            ok, r, t, inl = cv2.solvePnPRansac(world, image, K, None, reprojectionError=2.0, iterationsCount=200)
            if not ok or inl is None:
                continue
            r, t = cv2.solvePnPRefineLM(world[inl[:, 0]], image[inl[:, 0]], K, None, r, t)
            E = np.eye(4)
            E[:3, :3] = cv2.Rodrigues(r)[0]
            E[:3, 3] = t[:, 0]
            errors.append(angle_deg(np.linalg.inv(np.linalg.inv(gt[i + step]) @ gt[i]) @ E))
        print(f"PnP {step} frame(s) apart, {levels}-level pyramid: median rotation error "
              f"{np.median(errors):.4f} deg over {len(errors)} pairs")


def main():
    if len(sys.argv) >= 4 and sys.argv[1] == "run":
        run(sys.argv[2], sys.argv[3])
    elif len(sys.argv) in (3, 4) and sys.argv[1] == "pnp":
        pnp(sys.argv[2], int(sys.argv[3]) if len(sys.argv) == 4 else 1)
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
