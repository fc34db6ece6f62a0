#!/usr/bin/env python3
"""The library's keypoint depth against the simulator's exact depth, by surface and by sample distance.

    PYTHONPATH=build/release/python scripts/keypoint_depth_truth.py SEQ [--every N] [--surface-step PX]
        [--fixed-kernel] [--accumulate FULL_SEQ [--neighbours N] [--window PX]]

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
SEQ, the original as FULL_SEQ), every N-th frame from the 5th to the 5th-last: the truth is FULL_SEQ's scans of the
N frames either side (--neighbours, default 5) moved into the frame by the ground-truth poses, and the
keypoint's ray met with a plane through their points that project within PX pixels of it (--window,
default 1: 3 x 3 pixels) (the nearest surface: within
3 % of their 10th-percentile depth; at least 8 points, within 3 cm of the plane, else no truth). So
only keypoints on locally flat surfaces are graded, and the class is the plane's: level where its
normal is within 26 deg of vertical. No z-buffer: a z-buffered image reads short wherever the depth
changes fast across a pixel (the road near the car, about 0.4 % on 04). It still carries the truth
poses' errors; it shares the scans' calibration, so it cannot see a LiDAR-camera misalignment.
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
parser.add_argument("--neighbours", type=int, default=5)
parser.add_argument("--window", type=int, default=1)
args = parser.parse_args()


class AccumulatedScans:
    """the neighbouring frames' full scans in frame i's camera 0, indexed by the pixel they project to"""

    def __init__(self, full, i, calibration, shape):
        P = calibration.P_img_lidar
        self.K = P[:, :3] @ np.linalg.inv(calibration.T_cam_lidar[:3, :3])  # the intrinsics of P = K [R | t]
        self.width = shape[1]
        T_i = full.load(i).T_world_cam0
        clouds = []
        for j in range(max(0, i - args.neighbours), min(len(full), i + args.neighbours + 1)):
            if j == i:
                continue
            other = full.load(j)
            M = np.linalg.inv(T_i) @ other.T_world_cam0 @ calibration.T_cam_lidar
            x = other.scan[:, :3].astype(np.float64) @ M[:3, :3].T + M[:3, 3]
            clouds.append(x[x[:, 2] > 1.0])
        points = np.vstack(clouds)
        uvw = points @ self.K.T
        u, v = uvw[:, 0] / uvw[:, 2], uvw[:, 1] / uvw[:, 2]
        inside = (u >= 0) & (v >= 0) & (u < shape[1]) & (v < shape[0])
        pixel = np.floor(v[inside]).astype(np.int64) * shape[1] + np.floor(u[inside]).astype(np.int64)
        order = np.argsort(pixel)
        self.pixel, self.points = pixel[order], points[inside][order]

    def plane_depth(self, x, y):
        """(depth where the ray through (x, y) meets the local plane, the plane's class), or None"""
        r = range(-args.window, args.window + 1)
        ids = [(int(y) + dy) * self.width + int(x) + dx for dy in r for dx in r]
        lo, hi = np.searchsorted(self.pixel, ids), np.searchsorted(self.pixel, ids, "right")
        q = self.points[np.concatenate([np.arange(a, b) for a, b in zip(lo, hi)])]
        if len(q) < 8:
            return None
        q = q[q[:, 2] < 1.03 * np.percentile(q[:, 2], 10)]
        if len(q) < 8:
            return None
        centre = q.mean(axis=0)
        _, singular, vt = np.linalg.svd(q - centre)
        normal = vt[2]
        if singular[2] / np.sqrt(len(q)) > 0.03:
            return None
        ray = np.linalg.solve(self.K, np.array([x, y, 1.0]))
        depth = normal @ centre / (normal @ ray)
        return (depth, "level" if abs(normal[1]) > 0.9 else "other") if depth > 0 else None


def exact_surface(truth, u, v):
    """the surface the simulator's exact depth shows around (u, v), from inverse depth over +-3 px"""
    window = truth[max(v - 3, 0):v + 4, max(u - 3, 0):u + 4]
    if window.shape != (7, 7) or not (window > 0).all():
        return "other"
    # relative change of inverse depth per pixel, across and down
    du = abs(1 / truth[v, u + 3] - 1 / truth[v, u - 3]) / 6 * truth[v, u]
    dv = abs(1 / truth[v + 3, u] - 1 / truth[v - 3, u]) / 6 * truth[v, u]
    if dv > 3 * du and dv > 1e-4:
        return "level"
    if du > 3 * dv and du > 1e-4:
        return "facade"
    return "frontal" if du <= 1e-4 and dv <= 1e-4 else "other"


camera0 = [True, False, False, False]  # the other cameras' images are not needed
seq = rgbl.open_sequence(args.seq, cameras=camera0)
full = rgbl.open_sequence(args.accumulate, cameras=camera0) if args.accumulate else None
source = rgbl.make_lidar_source(seq.calibration.camera(0), surface_step_px=args.surface_step,
                                kernel_from_ring_spacing=not args.fixed_kernel)
orb = rgbl.OrbExtractor()

rows = []  # (estimate, truth, sample distance, gradient, surface)
frames = range(0, len(seq), args.every) if full is None else range(5, len(seq) - 5, args.every)
for i in frames:
    frame = seq.load(i)
    image = frame.images[0]
    if full is None:
        truth = rgbl.read_depth_png(f"{args.seq}/depth/{i:06d}.png")
    else:
        scans = AccumulatedScans(full, i, seq.calibration.camera(0), image.shape)
    source.prepare(image, scan=frame.scan, index=i, timestamp=frame.timestamp)
    keypoints, _ = orb.extract(image)
    pixels = np.stack([keypoints["x"], keypoints["y"]], 1).astype(np.float32)
    for (x, y), (z, distance, spread, gradient) in zip(pixels, source.sample(pixels)):
        if z <= 0 or spread > max(1.0, 0.05 * z):
            continue
        if full is not None:
            plane = scans.plane_depth(x, y)
            if plane is not None:
                rows.append((z, plane[0], distance, gradient, plane[1]))
            continue
        u, v = int(round(x)), int(round(y))
        if truth[v, u] > 0:
            rows.append((z, truth[v, u], distance, gradient, exact_surface(truth, u, v)))

a = np.array([row[:4] for row in rows], np.float64)
surface = np.array([row[4] for row in rows])
error = (a[:, 0] - a[:, 1]) / a[:, 1]


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
for name in ("level", "facade", "frontal", "other"):
    report(name, surface == name)
