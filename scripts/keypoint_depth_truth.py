#!/usr/bin/env python3
"""The library's keypoint depth against the simulator's exact depth, by surface and by sample distance.

    PYTHONPATH=build/release/python scripts/keypoint_depth_truth.py SEQ [--every N] [--surface-step PX]
        [--fixed-kernel] [--accumulate FULL_SEQ]

SEQ: a simulator sequence whose depth/ folder holds camera 0's exact depth (`rgbl_sim --depth-camera 0`;
a copy thinned by scripts/degrade.py --rings keeps it). Every N-th frame (default 5): rgbl's ORB
keypoints, their depth from the `lidar` source with its defaults (LiDAR.SurfaceStepPx from
--surface-step; --fixed-kernel: LiDAR.KernelFromRingSpacing 0) against the exact depth at the
keypoint's pixel. Keypoints the tracker's noise model drops (spread under the kernel above max(1 m,
5 %)) are left out. The relative error (estimate - truth) / truth is printed for all of them, for those
the ring plane fit placed, by the distance to the sample the value came from, and by the surface the
truth shows around the keypoint (inverse depth over +-3 px): level (changing down the image: the
road), facade (changing across: a wall seen at an angle), frontal (neither) or other.
--accumulate FULL_SEQ: a real drive instead (e.g. a KITTI sequence thinned by degrade.py --rings as
SEQ, the original as FULL_SEQ): the truth is FULL_SEQ's scans of the 10 neighbouring frames moved into
the frame by the ground-truth poses, z-buffered, the median within 1 px of the keypoint (as
scripts/keypoint_depth_bias.py does); it carries the truth poses' errors and moving objects' smear.
Needs python3-numpy and the Python module.
"""
import argparse

import numpy as np
import rgbl

parser = argparse.ArgumentParser()
parser.add_argument("seq")
parser.add_argument("--every", type=int, default=5)
parser.add_argument("--surface-step", type=int, default=2)
parser.add_argument("--fixed-kernel", action="store_true")
parser.add_argument("--accumulate", metavar="FULL_SEQ")
args = parser.parse_args()


def accumulated_truth(full, i, calibration, shape):
    """the neighbouring frames' full scans in frame i's camera 0, z-buffered (0 = none)"""
    P = calibration.P_img_lidar
    K = P[:, :3] @ np.linalg.inv(calibration.T_cam_lidar[:3, :3])  # the intrinsics of P = K [R | t]
    T_i = full.load(i).T_world_cam0
    depth = np.zeros(shape, np.float32)
    for j in range(max(0, i - 5), min(len(full), i + 6)):
        if j == i:
            continue
        other = full.load(j)
        M = np.linalg.inv(T_i) @ other.T_world_cam0 @ calibration.T_cam_lidar
        d = rgbl.project_to_depth(other.scan, K @ M[:3, :], shape[1], shape[0])
        take = (d > 0) & ((depth == 0) | (d < depth))
        depth[take] = d[take]
    return depth


def truth_at(truth, u, v):
    if args.accumulate is None:
        return truth[v, u]
    near = truth[max(0, v - 1):v + 2, max(0, u - 1):u + 2]
    near = near[near > 0]
    return np.median(near) if len(near) else 0.0

seq = rgbl.open_sequence(args.seq)
full = rgbl.open_sequence(args.accumulate) if args.accumulate else None
source = rgbl.make_lidar_source(seq.calibration.camera(0), surface_step_px=args.surface_step,
                                kernel_from_ring_spacing=not args.fixed_kernel)
orb = rgbl.OrbExtractor()

rows = []
for i in range(0, len(seq), args.every):
    frame = seq.load(i)
    image = frame.images[0]
    if full is None:
        truth = rgbl.read_depth_png(f"{args.seq}/depth/{i:06d}.png")
    elif 5 <= i < len(seq) - 5:
        truth = accumulated_truth(full, i, seq.calibration.camera(0), image.shape)
    else:
        continue
    source.prepare(image, scan=frame.scan, index=i, timestamp=frame.timestamp)
    keypoints, _ = orb.extract(image)
    pixels = np.stack([keypoints["x"], keypoints["y"]], 1).astype(np.float32)
    for (x, y), (z, distance, spread, gradient) in zip(pixels, source.sample(pixels)):
        u, v = int(round(x)), int(round(y))
        z_true = truth_at(truth, u, v)
        if z <= 0 or not z_true > 0 or spread > max(1.0, 0.05 * z):
            continue
        window = truth[max(v - 3, 0):v + 4, max(u - 3, 0):u + 4]
        if window.shape != (7, 7) or not (window > 0).all():
            du = dv = np.nan
        else:  # relative change of inverse depth per pixel, across and down
            du = abs(1 / truth[v, u + 3] - 1 / truth[v, u - 3]) / 6 * truth[v, u]
            dv = abs(1 / truth[v + 3, u] - 1 / truth[v - 3, u]) / 6 * truth[v, u]
        rows.append((z, z_true, distance, gradient, du, dv))

a = np.array(rows)
error = (a[:, 0] - a[:, 1]) / a[:, 1]
du, dv = a[:, 4], a[:, 5]
level = (dv > 3 * du) & (dv > 1e-4)
facade = (du > 3 * dv) & (du > 1e-4)
frontal = (du <= 1e-4) & (dv <= 1e-4)


def report(name, mask):
    if not mask.any():
        print(f"{name:18s} n=0")
        return
    e = error[mask]
    print(f"{name:18s} n={mask.sum():6d}  median {np.median(e):+.4f}  mean {np.mean(e):+.4f}  "
          f"|error| > 5 %: {np.mean(np.abs(e) > 0.05):.3f}  > 20 %: {np.mean(np.abs(e) > 0.2):.3f}")


print(f"{args.seq}: {len(a)} keypoints with depth the tracker keeps, every {args.every}th frame")
report("all", np.ones(len(a), bool))
report("ring plane fit", a[:, 3] > 0)
for lo, hi in [(0, 1.5), (1.5, 3), (3, 5), (5, 8), (8, 32)]:
    report(f"sample {lo}-{hi} px", (a[:, 2] >= lo) & (a[:, 2] < hi))
report("level", level)
report("facade", facade)
report("frontal", frontal)
report("other", ~(level | facade | frontal))
