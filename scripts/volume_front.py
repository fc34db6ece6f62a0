#!/usr/bin/env python3
"""Where leaves are: can the LiDAR's front of a hedge be told from the geometry, and how far does moving a
keypoint's depth to it remove the surface mean's bias? Two rules, graded against the simulator's exact
depth (docs/accuracy.md, "Seeds never looked at, and the LiDAR's share of each scenario's error").

  PYTHONPATH=build/release/python scripts/volume_front.py window SEQ [--frames A B] [--deg D] [--gate K] [--band F]
  PYTHONPATH=build/release/python scripts/volume_front.py landmark SEQ [--span N] [--radius R] [--allow S]
  PYTHONPATH=build/release/python scripts/volume_front.py kernel SEQ [--span N]
  scripts/volume_front.py map SEQ --run RUN [--run RUN2 ...]
  PYTHONPATH=build/release/python scripts/volume_front.py road SEQ

SEQ: a street rendered with its exact depth images (sequences/00 of `rgbl demo --depth precomputed
--keep DIR`, or a street in the accuracy suite's cache, ~/.cache/rgbl/scenarios/<name>/sequences/00).

`window`: one scan. At each ORB keypoint with depth from the library's `lidar` source (ring fit 0.5 deg)
the samples of the sparse projection within +-D deg by 5 rows and within F of its depth get a plane in
inverse depth; where they scatter about it by more than K range sigmas (0.02 m) the keypoint moves to
the plane's lowest sample less the noise's expected minimum. Prints the relative depth error before
and after, on the hedge (x >= 300 px, nearer than 10 m) and elsewhere.

`landmark`: over frames. The keypoints of every 10th frame, placed by the exact depth, are followed
through the next N frames with the true poses; the scans' points within R of each accumulate in the
world. A plane fitted to them, the residuals' spread and skewness along its normal tell a volume
(leaves) from a surface, and their 5th percentile (less S range sigmas) is its front. Prints, for
landmarks whose surface-mean depth is > 1 % too far ("biased"), within 0.3 % ("clean") and the rest, how often
each gate fires and the mean relative bias before and after moving the depth to the front. The true
poses make this an upper bound of what a tracker's own poses would give.

`kernel`: over frames, from the keypoint's kernel alone. The same landmarks are projected into the
next N frames; at each, the library's surface mean and the kernel's minimum (`lidar:dilated`). Prints
the median gap between the two per landmark, biased against clean: whether the kernel's minimum,
taken over frames, marks a front.

`map`: how deep a run's map reads the hedge. The landmarks of RUN's map.ply (an `rgbl run --out` folder
of SEQ), seen from the run's own pose of every 10th frame, against the exact depth at their pixels
(within 5 %): the median and mean relative error nearer than 10 m on the right (x >= 300 px) and
elsewhere, then by image third, below the camera and by distance.

`road`: the library's `lidar` source on the road ahead, frame by frame: the median relative depth
error of the keypoints in the image's middle third more than 1.2 m below the camera (every 5th frame),
with the ring fit (0.5 deg) and without. Tells a source's bias from a map read from drifted poses.

Needs python3-numpy, python3-opencv, python3-scipy and the Python module.
"""
import argparse
import importlib.util
import os

import cv2
import numpy as np
import rgbl

SIGMA = 0.02  # the simulator's range noise, m

_spec = importlib.util.spec_from_file_location(
    'kdb', os.path.join(os.path.dirname(os.path.abspath(__file__)), 'keypoint_depth_bias.py'))
kdb = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(kdb)


class Street:
    def __init__(self, seq):
        self.seq = seq
        self.P, self.Tr = kdb.read_calibration(os.path.join(seq, 'calib.txt'))
        self.frames = sorted(os.listdir(os.path.join(seq, 'image_0')))
        poses = np.loadtxt(os.path.join(seq, '..', '..', 'poses', '00.txt')).reshape(-1, 3, 4)
        self.T = [np.vstack([p, [0, 0, 0, 1]]) for p in poses]
        self.fx, self.fy, self.cx, self.cy = self.P[0, 0], self.P[1, 1], self.P[0, 2], self.P[1, 2]
        h, w = self.image(0).shape
        self.shape = (h, w)
        self.camera = rgbl.PinholeCamera(self.fx, self.fy, self.cx, self.cy, w, h)
        self.calibration = rgbl.CameraCalibration(self.camera, T_cam_lidar=self.Tr)

    def image(self, t):
        return cv2.imread(os.path.join(self.seq, 'image_0', self.frames[t]), cv2.IMREAD_GRAYSCALE)

    def raw(self, t):
        return np.fromfile(os.path.join(self.seq, 'velodyne', f'{t:06d}.bin'), np.float32).reshape(-1, 4)

    def exact(self, t):
        return cv2.imread(os.path.join(self.seq, 'depth', self.frames[t]), cv2.IMREAD_UNCHANGED).astype(np.float64) / 256.0

    def world_point(self, t, u, v, z):
        """the point at pixel (u, v) and depth z of frame t, in the world (true poses)"""
        return (self.T[t] @ np.array([*self.camera.unproject((float(u), float(v)), float(z)), 1.0]))[:3]

    def windows(self, span):
        """(first frame K, frames K..K+span) of every 10th frame, as the over-frames rules follow them"""
        n = len(self.frames)
        return [(K, range(K, min(n, K + span + 1))) for K in range(0, n - 5, 10)]


def window_rule(street, first, last, deg, gate, band):
    source = rgbl.make_lidar_source(street.calibration, surface_fit_window_deg=0.5)
    half = max(2, int(round(np.tan(np.radians(deg)) * street.fx)))
    orb = cv2.ORB_create(2000)
    rows = []
    for t in range(first, min(last, len(street.frames) - 1) + 1):
        image, raw, truth = street.image(t), street.raw(t), street.exact(t)
        scan = raw[:, :3].astype(np.float64)
        sparse = kdb.project((street.Tr[:3, :3] @ scan.T + street.Tr[:3, 3:4]).T, street.P, image.shape)
        pixels = np.array([k.pt for k in orb.detect(image, None)], np.float32).reshape(-1, 2)
        source.prepare(image, raw)
        for (px, py), (z, _, spread, _) in zip(pixels, np.asarray(source.sample(pixels))):
            if not z > 0 or spread > max(1.0, 0.05 * z):
                continue
            x, y = int(np.floor(px + .5)), int(np.floor(py + .5))
            true_z = truth[y, x]
            if not true_z > 0 or abs(z / true_z - 1) > 0.2:
                continue
            y0, x0 = max(0, y - 2), max(0, x - half)
            win = sparse[y0:y + 3, x0:x + half + 1]
            vv, uu = np.nonzero(np.isfinite(win))
            d = win[vv, uu]
            keep = np.abs(d - z) < band * z
            moved, scatter, skew = z, 0.0, 0.0
            if keep.sum() >= 6:
                A = np.c_[np.ones(keep.sum()), uu[keep] + x0 - px, vv[keep] + y0 - py]
                coef, *_ = np.linalg.lstsq(A, 1.0 / d[keep], rcond=None)
                r = d[keep] - 1.0 / (A @ coef)
                scatter = np.sqrt(np.sum(r ** 2) / max(1, len(r) - 3))
                skew = np.mean(r ** 3) / max(np.mean(r ** 2), 1e-12) ** 1.5
                if scatter > gate * SIGMA:
                    moved = min(z, z + r.min() + SIGMA * np.sqrt(2 * np.log(len(r))))
            rows.append((x, z, moved, true_z, scatter, skew))
    a = np.array(rows)
    before, after = a[:, 1] / a[:, 3] - 1, a[:, 2] / a[:, 3] - 1
    fired = a[:, 2] < a[:, 1]
    hedge = (a[:, 0] >= 300) & (a[:, 3] < 10)
    print(f'{street.seq}: window +-{half} px, gate {gate} sigma, band {band}: fires on {100 * fired.mean():.1f} % of {len(a)}')
    for name, m in (('all', np.ones(len(a), bool)), ('hedge (x >= 300, z < 10)', hedge), ('elsewhere', ~hedge),
                    ('elsewhere, fired', ~hedge & fired)):
        if m.any():
            print(f'  {name:26s} n={m.sum():5d}  mean {100 * before[m].mean():+.2f} % -> {100 * after[m].mean():+.2f} %, '
                  f'median {100 * np.median(before[m]):+.2f} % -> {100 * np.median(after[m]):+.2f} %')
    # does the residuals' skewness tell leaves (one-sided) from geometry where the samples scatter?
    for name, m in (('hedge', hedge), ('elsewhere', ~hedge)):
        wide = m & (a[:, 4] > 4 * SIGMA)
        if wide.sum() > 5:
            print(f'  skewness where the scatter exceeds 4 sigma, {name}: quartiles '
                  f'{np.round(np.percentile(a[wide, 5], [25, 50, 75]), 2)} ({wide.sum()} keypoints)')


def landmark_rule(street, span, radius, allow):
    from scipy.spatial import cKDTree
    source = rgbl.make_lidar_source(street.calibration, surface_fit_window_deg=0.5)
    orb = cv2.ORB_create(2000)

    def scan_world(t):
        p = street.raw(t)[:, :3].astype(np.float64)
        M = street.T[t] @ street.Tr
        return (M[:3, :3] @ p.T + M[:3, 3:4]).T

    rows = []  # z, bias, spread, skew, depth moved to the front, true surface beyond the 5th percentile
    windows = street.windows(span)
    marks = {}  # K -> [(world point, true z, surface-mean bias)]
    for K, _ in windows:
        image, raw, truth = street.image(K), street.raw(K), street.exact(K)
        pixels = np.array([k.pt for k in orb.detect(image, None)], np.float32).reshape(-1, 2)
        source.prepare(image, raw)
        marks[K] = []
        for (u, v), (z, _, spread, _) in zip(pixels, np.asarray(source.sample(pixels))):
            true_z = truth[int(np.floor(v + .5)), int(np.floor(u + .5))]
            if 1 < true_z < 30 and z > 0 and spread <= max(1.0, 0.05 * z):
                marks[K].append((street.world_point(K, u, v, true_z), true_z, z - true_z))
    gathered = {K: [[] for _ in marks[K]] for K, _ in windows}
    for t in range(len(street.frames)):  # each scan once, for every window that holds it
        active = [K for K, frames in windows if t in frames and marks[K]]
        if not active:
            continue
        points = scan_world(t)
        tree = cKDTree(points)
        for K in active:
            for j, near in enumerate(tree.query_ball_point(np.array([m[0] for m in marks[K]]), radius)):
                if near:
                    gathered[K][j].append(points[near])
    for K, _ in windows:
        centre_K = street.T[K][:3, 3]
        for (x, true_z, bias), parts in zip(marks[K], gathered[K]):
            if not parts:
                continue
            Q = np.vstack(parts)
            if len(Q) < 15:
                continue
            c = Q.mean(0)
            n = np.linalg.eigh(np.cov((Q - c).T))[1][:, 0]
            ray_per_z = (x - centre_K) / true_z
            if n @ ray_per_z < 0:
                n = -n  # pointing away from the camera
            r = (Q - c) @ n
            s = r.std()
            skew = np.mean(r ** 3) / max(s ** 3, 1e-12)
            front = np.percentile(r, 5) + allow * SIGMA
            # the surface mean's point on the keypoint's ray, moved along the ray onto the front plane
            distance = (centre_K + ray_per_z * (true_z + bias) - c) @ n - front
            dz = distance / (n @ ray_per_z) if abs(n @ ray_per_z) > 0.2 else 0.0
            rows.append((true_z, bias, s, skew, dz, (x - c) @ n - np.percentile(r, 5)))
    a = np.array(rows)
    rel = a[:, 1] / a[:, 0]
    biased, clean = rel > 0.01, np.abs(rel) < 0.003
    print(f'{street.seq}: {len(a)} landmarks, radius {radius} m, {span} frames, front allowance {allow} sigma')
    for name, m in (('biased (> 1 %)', biased), ('clean (< 0.3 %)', clean)):
        if m.any():
            print(f'  {name:16s} n={m.sum():5d}  spread / sigma q10/50/90 {np.round(np.percentile(a[m, 2] / SIGMA, [10, 50, 90]), 1)}'
                  f'  skew q10/50/90 {np.round(np.percentile(a[m, 3], [10, 50, 90]), 2)}'
                  f'  true surface - 5th percentile, median {np.median(a[m, 5]):+.3f} m')
    for spread_gate, skew_gate in ((2, 0.3), (3, 0.3), (3, 0.5), (4, 0.5)):
        fire = (a[:, 2] > spread_gate * SIGMA) & (a[:, 3] > skew_gate)
        after = (a[:, 1] - np.where(fire, a[:, 4], 0.0)) / a[:, 0]
        line = f'  spread > {spread_gate} sigma, skew > {skew_gate}: fires on'
        for name, m in (('biased', biased), ('clean', clean), ('the rest', ~biased & ~clean)):
            if m.any():
                line += f' {100 * fire[m].mean():.0f} % of {name} ({100 * rel[m].mean():+.2f} -> {100 * after[m].mean():+.2f} %),'
        print(line + f' all {100 * rel.mean():+.2f} -> {100 * after.mean():+.2f} %')


def kernel_rule(street, span):
    mean_source = rgbl.make_lidar_source(street.calibration, surface_fit_window_deg=0.5)
    min_source = rgbl.make_depth_source('lidar:dilated', street.calibration)
    orb = cv2.ORB_create(2000)
    h, w = street.shape
    rows = []  # bias of the surface mean (median over frames), gap mean - minimum (median over frames)
    windows = street.windows(span)
    marks = {}  # K -> world points of its keypoints
    for K, _ in windows:
        truth = street.exact(K)
        marks[K] = []
        for k in orb.detect(street.image(K), None):
            true_z = truth[int(np.floor(k.pt[1] + .5)), int(np.floor(k.pt[0] + .5))]
            if 1 < true_z < 40:
                marks[K].append(np.append(street.world_point(K, k.pt[0], k.pt[1], true_z), 1.0))
    seen = {K: [[] for _ in marks[K]] for K, _ in windows}
    for t in range(len(street.frames)):  # each frame prepared once, for every window that holds it
        active = [K for K, frames in windows if t in frames]
        if not active:
            continue
        exact = street.exact(t)
        inverse = np.linalg.inv(street.T[t])
        pixels, which, depths = [], [], []
        for K in active:
            for j, X in enumerate(marks[K]):
                c = inverse @ X
                if c[2] < 1:
                    continue
                u, v = street.fx * c[0] / c[2] + street.cx, street.fy * c[1] / c[2] + street.cy
                if not (3 <= u < w - 3 and 3 <= v < h - 3):
                    continue
                if not abs(exact[int(np.floor(v + .5)), int(np.floor(u + .5))] / c[2] - 1) < 0.03:
                    continue  # hidden in frame t
                pixels.append((u, v)); which.append((K, j)); depths.append(c[2])
        if not pixels:
            continue
        image, raw = street.image(t), street.raw(t)
        pixels = np.array(pixels, np.float32)
        mean_source.prepare(image, raw); means = np.asarray(mean_source.sample(pixels))
        min_source.prepare(image, raw); minima = np.asarray(min_source.sample(pixels))[:, 0]
        for (K, j), z, (zm, _, spread, _), zn in zip(which, depths, means, minima):
            if zm > 0 and zn > 0 and spread <= max(1.0, 0.05 * zm):
                seen[K][j].append((zm - z, zm - zn))
    for K, _ in windows:
        for o in seen[K]:
            if len(o) >= 8:
                o = np.array(o)
                rows.append((np.median(o[:, 0]), np.median(o[:, 1])))
    a = np.array(rows)
    print(f'{street.seq}: {len(a)} landmarks seen in >= 8 of {span + 1} frames')
    for name, m in (('biased (> 0.05 m)', a[:, 0] > 0.05), ('clean (< 0.02 m)', np.abs(a[:, 0]) < 0.02)):
        print(f'  {name:18s} n={m.sum():5d}  surface mean - kernel minimum q10/50/90 {np.round(np.percentile(a[m, 1], [10, 50, 90]), 3)} m')


def map_check(street, runs):
    for run in runs:
        lines = open(os.path.join(run, 'map.ply')).read().split('\n')
        n = int(next(line for line in lines if line.startswith('element vertex')).split()[-1])
        start = lines.index('end_header') + 1
        X = np.array([[float(v) for v in lines[start + i].split()[:3]] for i in range(n)])
        estimate = np.loadtxt(os.path.join(run, 'trajectory_kitti.txt')).reshape(-1, 3, 4)
        views = []
        for K in range(10, len(street.frames) - 5, 10):
            T_world_cam = np.vstack([estimate[K], [0, 0, 0, 1]])
            p = (np.linalg.inv(T_world_cam) @ np.c_[X, np.ones(n)].T).T[:, :3]
            exact = street.exact(K)
            for x, y, z in p:
                if not 1 < z < 30:
                    continue
                u = int(round(street.fx * x / z + street.cx))
                v = int(round(street.fy * y / z + street.cy))
                if not (0 <= u < exact.shape[1] and 0 <= v < exact.shape[0]):
                    continue
                t = exact[v, u]
                if t > 0 and abs(z / t - 1) <= 0.05:
                    views.append((u, t, z / t - 1, y))
        a = np.array(views)
        hedge = (a[:, 0] >= 300) & (a[:, 1] < 10)
        print(f'{run}: {len(a)} landmark views; hedge median {100 * np.median(a[hedge, 2]):+.2f} % mean '
              f'{100 * a[hedge, 2].mean():+.2f} % ({hedge.sum()}); elsewhere median {100 * np.median(a[~hedge, 2]):+.2f} % '
              f'mean {100 * a[~hedge, 2].mean():+.2f} %')
        third = street.shape[1] / 3
        for name, m in (('left third', a[:, 0] < third), ('middle third', (a[:, 0] >= third) & (a[:, 0] < 2 * third)),
                        ('right third', a[:, 0] >= 2 * third), ('over 1.2 m below the camera', a[:, 3] > 1.2),
                        ('nearer than 10 m', a[:, 1] < 10), ('10-20 m', (a[:, 1] >= 10) & (a[:, 1] < 20)),
                        ('20 m and more', a[:, 1] >= 20)):
            if m.sum() >= 5:
                print(f'  {name:28s} {m.sum():5d} views, median {100 * np.median(a[m, 2]):+.2f} %, '
                      f'share of the summed error {100 * a[m, 2].sum() / a[:, 2].sum():4.0f} %')


def road_check(street):
    sources = (rgbl.make_lidar_source(street.calibration, surface_fit_window_deg=0.5),
               rgbl.make_lidar_source(street.calibration, surface_fit_window_deg=0.0))
    orb = cv2.ORB_create(2000)
    h, w = street.shape
    medians = []
    for t in range(0, len(street.frames), 5):
        image, raw, exact = street.image(t), street.raw(t), street.exact(t)
        pixels = np.array([k.pt for k in orb.detect(image, None)], np.float32).reshape(-1, 2)
        samples = []
        for source in sources:
            source.prepare(image, raw)
            samples.append(np.asarray(source.sample(pixels)))
        errors = []
        for (u, v), fitted, plain in zip(pixels, samples[0], samples[1]):
            true_z = exact[int(np.floor(v + .5)), int(np.floor(u + .5))]
            if not (true_z > 0 and fitted[0] > 0 and plain[0] > 0) or fitted[2] > max(1.0, 0.05 * fitted[0]):
                continue
            below = (v - street.cy) * true_z / street.fy
            if below > 1.2 and w / 3 <= u < 2 * w / 3 and abs(fitted[0] / true_z - 1) < 0.2:
                errors.append((fitted[0] / true_z - 1, plain[0] / true_z - 1))
        if errors:
            e = np.array(errors)
            medians.append((t, np.median(e[:, 0]), np.median(e[:, 1])))
    m = np.array(medians)
    print(f'{street.seq}: road ahead, median per frame (fit / none): '
          + ' '.join(f'{int(t)}:{100 * a:+.2f}/{100 * b:+.2f}' for t, a, b in m))
    print(f'  median over the frames: {100 * np.median(m[:, 1]):+.3f} % with the fit, {100 * np.median(m[:, 2]):+.3f} % without')


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('mode', choices=('window', 'landmark', 'kernel', 'map', 'road'))
    parser.add_argument('seq')
    parser.add_argument('--frames', nargs=2, type=int, default=(0, 10))
    parser.add_argument('--deg', type=float, default=1.0)
    parser.add_argument('--gate', type=float, default=4.0)
    parser.add_argument('--band', type=float, default=0.1)
    parser.add_argument('--span', type=int, default=20)
    parser.add_argument('--radius', type=float, default=0.4)
    parser.add_argument('--allow', type=float, default=0.0)
    parser.add_argument('--run', action='append', default=[])
    args = parser.parse_args()
    street = Street(args.seq)
    if args.mode == 'window':
        window_rule(street, args.frames[0], args.frames[1], args.deg, args.gate, args.band)
    elif args.mode == 'road':
        road_check(street)
    elif args.mode == 'map':
        map_check(street, args.run)
    elif args.mode == 'landmark':
        landmark_rule(street, args.span, args.radius, args.allow)
    else:
        kernel_rule(street, args.span)


if __name__ == '__main__':
    main()
