#!/usr/bin/env python3
"""Does the LiDAR-camera calibration put the scan's depth edges on the image's edges?

  scripts/edge_alignment.py DRIVE [FRAMES]

DRIVE is a KITTI raw drive folder (calibration one level up) or an odometry sequence folder. On FRAMES
frames spread over the drive (default 20) the scan's depth discontinuities (a return nearer than a
neighbour along its ring by > 0.5 m, weighted by the square root of the step) are projected into
camera 0 with the calibration turned by small angles about the camera's x (pitch) and y (yaw) axes
(the points turned, +x moves them up), and scored by the image gradient there (Sobel, blurred 1.5
px): the targetless check of Levinson and Thrun (RSS 2013). A grid of 0.1 deg over +-1 deg, then
0.025 deg around the best. Prints the best turn and the score against the calibration as given; the
sign convention is that of scripts/extrinsic_sensitivity.py. Needs python3-numpy and python3-opencv.
"""
import glob
import os
import sys

import cv2
import numpy as np


def read_values(path):
    values = {}
    for line in open(path):
        if ':' not in line:
            continue
        key, rest = line.split(':', 1)
        try:
            values[key] = np.array([float(v) for v in rest.split()])
        except ValueError:
            pass
    return values


def calibration(drive):
    if os.path.exists(os.path.join(drive, 'calib.txt')):
        v = read_values(os.path.join(drive, 'calib.txt'))
        T = np.vstack([v['Tr'].reshape(3, 4), [0, 0, 0, 1]])
        images = sorted(glob.glob(os.path.join(drive, 'image_0', '*.png')))
        scans = sorted(glob.glob(os.path.join(drive, 'velodyne', '*.bin')))
        return v['P0'].reshape(3, 4), T, images, scans
    day = os.path.dirname(os.path.abspath(drive))
    v = read_values(os.path.join(day, 'calib_velo_to_cam.txt'))
    c = read_values(os.path.join(day, 'calib_cam_to_cam.txt'))
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = v['R'].reshape(3, 3), v['T']
    rect = np.eye(4)
    rect[:3, :3] = c['R_rect_00'].reshape(3, 3)
    images = sorted(glob.glob(os.path.join(drive, 'image_00', 'data', '*.png')))
    scans = sorted(glob.glob(os.path.join(drive, 'velodyne_points', 'data', '*.bin')))
    return c['P_rect_00'].reshape(3, 4), rect @ T, images, scans


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__)
    P, T, images, scans = calibration(argv[1])
    count = int(argv[2]) if len(argv) > 2 else 20
    frames = []
    for f in np.linspace(0, min(len(images), len(scans)) - 1, count).astype(int):
        image = cv2.imread(images[f], cv2.IMREAD_GRAYSCALE).astype(np.float32)
        edges = np.hypot(cv2.Sobel(image, cv2.CV_32F, 1, 0), cv2.Sobel(image, cv2.CV_32F, 0, 1))
        edges = cv2.GaussianBlur(edges, (0, 0), 1.5)
        edges /= edges.max()
        points = np.fromfile(scans[f], np.float32).reshape(-1, 4)[:, :3].astype(np.float64)
        r = np.linalg.norm(points, axis=1)
        step = np.zeros(len(r))  # KITTI stores a scan ring by ring
        step[1:-1] = np.maximum(np.maximum(r[:-2] - r[1:-1], r[2:] - r[1:-1]), 0.0)
        keep = (step > 0.5) & (r > 3) & (r < 50)
        frames.append((edges, (T[:3, :3] @ points[keep].T).T + T[:3, 3], np.sqrt(np.minimum(step[keep], 5.0))))

    def score(pitch, yaw):
        a, b = np.radians(pitch), np.radians(yaw)
        Rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
        Ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
        total = 0.0
        for edges, camera_points, weight in frames:
            q = (Ry @ Rx @ camera_points.T).T
            front = q[:, 2] > 1.0
            uvw = (P[:, :3] @ q[front].T).T + P[:, 3]
            u, v = uvw[:, 0] / uvw[:, 2], uvw[:, 1] / uvw[:, 2]
            inside = (u >= 0) & (u < edges.shape[1] - 1) & (v >= 0) & (v < edges.shape[0] - 1)
            total += (weight[front][inside] * edges[np.round(v[inside]).astype(int),
                                                     np.round(u[inside]).astype(int)]).sum()
        return total

    coarse = np.arange(-1.0, 1.0001, 0.1)
    grid = np.array([[score(p, y) for y in coarse] for p in coarse])
    i, j = np.unravel_index(grid.argmax(), grid.shape)
    fine = np.arange(-0.15, 0.1501, 0.025)
    grid = np.array([[score(coarse[i] + p, coarse[j] + y) for y in fine] for p in fine])
    k, m = np.unravel_index(grid.argmax(), grid.shape)
    pitch, yaw = coarse[i] + fine[k], coarse[j] + fine[m]
    print(f'best turn: pitch {pitch:+.3f} deg, yaw {yaw:+.3f} deg; score {grid.max() / score(0.0, 0.0):.4f} x the '
          f'calibration\'s; pitch profile at that yaw: ' +
          ' '.join(f'{p:+.1f}:{score(p, yaw) / grid.max():.3f}' for p in np.arange(-0.6, 0.61, 0.2)))


if __name__ == '__main__':
    main(sys.argv)
