#!/usr/bin/env python3
"""Bias of the keypoint depth from the 5x5 diamond: the dilation's minimum against the surface mean.

  scripts/keypoint_depth_bias.py real ../shared/data/kitti/odometry/sequences/04 ../shared/data/kitti/odometry/poses/04.txt
  rgbl demo --scenario plain --seed 1 --frames 20 --depth precomputed --keep /tmp/plain1
  scripts/keypoint_depth_bias.py sim /tmp/plain1/sequences/00

At ORB keypoints (OpenCV's, 2000 per frame) the scan is projected into camera 0 and both rules of
src/depth/completion.cpp are applied (`lookup_depth`: the nearest depth under the kernel;
`lookup_surface_depth`: the inverse-distance-weighted inverse-depth mean of the samples connected to
the nearest one by steps of at most 5 %), restated here in Python because the library exports no
keypoint-level lookup to scripts: keep the two in step with completion.cpp. Keypoints whose kernel spans a depth edge (spread >
max(1 m, 5 %), dropped by the tracker's noise model) are left out. Truth: the simulator's exact depth
image, or for KITTI the scans of the 10 neighbouring frames moved by the ground-truth poses (the
median within 1 px; z-buffered, it reads short where the depth changes fast across a pixel: the road
near the car, about 0.4 % on 04, docs/accuracy.md "A ring's samples 3 px apart";
scripts/keypoint_depth_truth.py --accumulate meets the ray with a plane instead). Also prints how many LiDAR rows the kernels hold: the minimum's bias comes from
the rows the kernel spans. Needs python3-numpy and python3-opencv.

  scripts/keypoint_depth_bias.py MODE SEQ [POSES] [--fit DEG] [--frames FIRST LAST]

--frames grades only those frames (the simulator: every frame between them; KITTI: every 4th of 5-45).

With the Python module on PYTHONPATH (build/release/python), --fit also grades the library's own
`lidar` source (rgbl.make_lidar_source: the surface mean after the occlusion filter) against the same
source with the ring plane fit of DEG (LiDAR.SurfaceFitWindowDeg), on the keypoints where both give
depth, over all of them and over those the fit moves by more than 0.1 %.
"""
import os
import sys

import cv2
import numpy as np

CELLS = [(dx, dy) for dy in range(-2, 3) for dx in range(-(2 - abs(dy)), 3 - abs(dy))]
TOLERANCE = 0.05


def read_calibration(path):
    values = {}
    for line in open(path):
        if ':' in line:
            key, rest = line.split(':', 1)
            values[key] = np.array([float(v) for v in rest.split()])
    return values['P0'].reshape(3, 4), np.vstack([values['Tr'].reshape(3, 4), [0, 0, 0, 1]])


def read_scan(path):
    return np.fromfile(path, np.float32).reshape(-1, 4)[:, :3].astype(np.float64)


def project(points_cam, P, shape):
    """z-buffered sparse depth image of camera-frame points"""
    points_cam = points_cam[points_cam[:, 2] > 0.5]
    uvw = (P[:, :3] @ points_cam.T + P[:, 3:4]).T
    u = np.floor(uvw[:, 0] / uvw[:, 2] + 0.5).astype(int)
    v = np.floor(uvw[:, 1] / uvw[:, 2] + 0.5).astype(int)
    z = uvw[:, 2]
    keep = (u >= 0) & (v >= 0) & (u < shape[1]) & (v < shape[0])
    image = np.full(shape, np.inf)
    order = np.argsort(-z[keep])  # nearest written last
    image[v[keep][order], u[keep][order]] = z[keep][order]
    return image


def keypoint_depths(sparse, px, py):
    """(minimum, surface mean, spread, rows) at a keypoint, or None without samples"""
    x, y = int(np.floor(px + 0.5)), int(np.floor(py + 0.5))
    samples = [(x + dx, y + dy, sparse[y + dy, x + dx]) for dx, dy in CELLS
               if 0 <= x + dx < sparse.shape[1] and 0 <= y + dy < sparse.shape[0] and np.isfinite(sparse[y + dy, x + dx])]
    if not samples:
        return None
    a = np.array(samples)
    nearest = int(np.argmin(a[:, 2]))
    on = np.zeros(len(a), bool)
    on[nearest] = True
    grown = True
    while grown:
        grown = False
        for i in np.flatnonzero(~on):
            for j in np.flatnonzero(on):
                if abs(a[i, 0] - a[j, 0]) <= 2 and abs(a[i, 1] - a[j, 1]) <= 2 and \
                        abs(a[i, 2] - a[j, 2]) <= TOLERANCE * min(a[i, 2], a[j, 2]):
                    on[i] = grown = True
                    break
    s = a[on]
    w = 1.0 / np.maximum(np.hypot(s[:, 0] - px, s[:, 1] - py), 0.5)
    return a[:, 2].min(), np.sum(w) / np.sum(w / s[:, 2]), a[:, 2].max() - a[:, 2].min(), len(set(a[:, 1]))


def take_option(name, count, cast):
    """the values after `name` in argv (one value, or a tuple of `count`), removed from it; None without it"""
    if name not in sys.argv:
        return None
    i = sys.argv.index(name)
    values = tuple(cast(v) for v in sys.argv[i + 1:i + 1 + count])
    del sys.argv[i:i + 1 + count]
    return values[0] if count == 1 else values


def main():
    fit_deg = take_option('--fit', 1, float)
    first_last = take_option('--frames', 2, int)
    if len(sys.argv) < 3 or sys.argv[1] not in ('real', 'sim'):
        sys.exit(__doc__)
    mode, seq = sys.argv[1], sys.argv[2]
    P, Tr = read_calibration(os.path.join(seq, 'calib.txt'))
    frames = sorted(os.listdir(os.path.join(seq, 'image_0')))
    if mode == 'real':
        poses = np.loadtxt(sys.argv[3]).reshape(-1, 3, 4)
        pose = lambda i: np.vstack([poses[i], [0, 0, 0, 1]])
        chosen = range(5, min(len(frames) - 5, 46), 4)
    else:
        chosen = range(0, min(len(frames), 8))
    if first_last is not None:
        first, last = first_last
        if mode == 'real':
            chosen = [i for i in chosen if first <= i <= last]
        else:
            chosen = range(first, min(len(frames), last + 1))
    orb = cv2.ORB_create(2000)
    errors, rows = [], []
    library = []  # (surface mean, plane fit) relative errors from rgbl's own lidar source
    sources = None
    for i in chosen:
        image = cv2.imread(os.path.join(seq, 'image_0', frames[i]), cv2.IMREAD_GRAYSCALE)
        raw = np.fromfile(os.path.join(seq, 'velodyne', f'{i:06d}.bin'), np.float32).reshape(-1, 4)
        scan = raw[:, :3].astype(np.float64)
        if fit_deg is not None and sources is None:
            import rgbl  # build/release/python on PYTHONPATH
            camera = rgbl.PinholeCamera(P[0, 0], P[1, 1], P[0, 2], P[1, 2], image.shape[1], image.shape[0])
            calibration = rgbl.CameraCalibration(camera, T_cam_lidar=Tr)
            sources = (rgbl.make_lidar_source(calibration, surface_fit_window_deg=0.0),
                       rgbl.make_lidar_source(calibration, surface_fit_window_deg=fit_deg))
        sparse = project((Tr[:3, :3] @ scan.T + Tr[:3, 3:4]).T, P, image.shape)
        if mode == 'real':
            clouds = []
            for j in range(i - 5, i + 6):
                if j == i:
                    continue
                M = np.linalg.inv(pose(i)) @ pose(j) @ Tr
                clouds.append((M[:3, :3] @ read_scan(os.path.join(seq, 'velodyne', f'{j:06d}.bin')).T + M[:3, 3:4]).T)
            truth_image = project(np.vstack(clouds), P, image.shape)
        else:
            truth_image = cv2.imread(os.path.join(seq, 'depth', frames[i]), cv2.IMREAD_UNCHANGED).astype(np.float64) / 256.0
            truth_image[truth_image <= 0] = np.inf
        keypoints = orb.detect(image, None)
        lib = None
        if sources is not None:
            pixels = np.array([k.pt for k in keypoints], np.float32).reshape(-1, 2)
            lib = []
            for source in sources:
                source.prepare(image, raw)
                lib.append(source.sample(pixels)[:, 0])
        for index, k in enumerate(keypoints):
            px, py = k.pt
            r = keypoint_depths(sparse, px, py)
            if r is None or r[2] > max(1.0, 0.05 * r[0]) or r[0] > 80:
                continue
            x, y = int(np.floor(px + 0.5)), int(np.floor(py + 0.5))
            near = truth_image[max(0, y - 1):y + 2, max(0, x - 1):x + 2] if mode == 'real' else truth_image[y:y + 1, x:x + 1]
            near = near[np.isfinite(near)]
            if len(near) == 0:
                continue
            truth = np.median(near)
            errors.append(((r[0] - truth) / truth, (r[1] - truth) / truth))
            rows.append(r[3])
            if lib is not None and lib[0][index] > 0 and lib[1][index] > 0:
                library.append(((lib[0][index] - truth) / truth, (lib[1][index] - truth) / truth))
    errors = np.array(errors)
    print(f'{seq}: {len(errors)} keypoints with depth and truth (relative errors within +-20 %)')
    for column, name in ((0, 'minimum (lidar:dilated)'), (1, 'surface mean (lidar)')):
        e = errors[:, column]
        e = e[np.abs(e) < 0.2]
        print(f'  {name:24s} median {100 * np.median(e):+.2f} %  mean {100 * np.mean(e):+.2f} %  '
              f'median |error| {100 * np.median(np.abs(e)):.2f} %')
    if fit_deg is not None:
        library = np.array(library)
        library = library[np.all(np.abs(library) < 0.2, axis=1)]
        moved = np.abs((1 + library[:, 1]) / (1 + library[:, 0]) - 1) > 0.001
        print(f'  the library\'s lidar source, {len(library)} keypoints ({100 * moved.mean():.0f} % moved by the fit):')
        for subset, label in ((np.ones(len(library), bool), 'all'), (moved, 'moved')):
            for column, name in ((0, 'surface mean'), (1, f'plane fit {fit_deg:g} deg')):
                e = library[subset, column]
                print(f'    {label:5s} {name:18s} median {100 * np.median(e):+.2f} %  mean {100 * np.mean(e):+.2f} %  '
                      f'median |error| {100 * np.median(np.abs(e)):.2f} %  rms {100 * np.sqrt(np.mean(e ** 2)):.2f} %')
    counts = np.bincount(np.array(rows))
    print('  LiDAR rows under the kernel: ' + ', '.join(f'{r}: {100 * c / len(rows):.0f} %' for r, c in enumerate(counts) if c))


if __name__ == '__main__':
    main()
