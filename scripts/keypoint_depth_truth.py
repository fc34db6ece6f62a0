#!/usr/bin/env python3
"""The library's keypoint depth against the simulator's exact depth, by surface and by sample distance.

    PYTHONPATH=build/release/python scripts/keypoint_depth_truth.py SEQ [--every N] [--surface-step PX]
        [--fixed-kernel]

SEQ: a simulator sequence whose depth/ folder holds camera 0's exact depth (`rgbl_sim --depth-camera 0`;
a copy thinned by scripts/degrade.py --rings keeps it). Every N-th frame (default 5): rgbl's ORB
keypoints, their depth from the `lidar` source with its defaults (LiDAR.SurfaceStepPx from
--surface-step; --fixed-kernel: LiDAR.KernelFromRingSpacing 0) against the exact depth at the
keypoint's pixel. Keypoints the tracker's noise model drops (spread under the kernel above max(1 m,
5 %)) are left out. The relative error (estimate - truth) / truth is printed for all of them, for those
the ring plane fit placed, by the distance to the sample the value came from, and by the surface the
truth shows around the keypoint (inverse depth over +-3 px): level (changing down the image: the
road), facade (changing across: a wall seen at an angle), frontal (neither) or other.
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
args = parser.parse_args()

seq = rgbl.open_sequence(args.seq)
source = rgbl.make_lidar_source(seq.calibration.camera(0), surface_step_px=args.surface_step,
                                kernel_from_ring_spacing=not args.fixed_kernel)
orb = rgbl.OrbExtractor()

rows = []
for i in range(0, len(seq), args.every):
    frame = seq.load(i)
    image = frame.images[0]
    truth = rgbl.read_depth_png(f"{args.seq}/depth/{i:06d}.png")
    source.prepare(image, scan=frame.scan, index=i, timestamp=frame.timestamp)
    keypoints, _ = orb.extract(image)
    pixels = np.stack([keypoints["x"], keypoints["y"]], 1).astype(np.float32)
    for (x, y), (z, distance, spread, gradient) in zip(pixels, source.sample(pixels)):
        u, v = int(round(x)), int(round(y))
        if z <= 0 or not truth[v, u] > 0 or spread > max(1.0, 0.05 * z):
            continue
        window = truth[max(v - 3, 0):v + 4, max(u - 3, 0):u + 4]
        if window.shape != (7, 7) or not (window > 0).all():
            du = dv = np.nan
        else:  # relative change of inverse depth per pixel, across and down
            du = abs(1 / truth[v, u + 3] - 1 / truth[v, u - 3]) / 6 * truth[v, u]
            dv = abs(1 / truth[v + 3, u] - 1 / truth[v - 3, u]) / 6 * truth[v, u]
        rows.append((z, truth[v, u], distance, gradient, du, dv))

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
