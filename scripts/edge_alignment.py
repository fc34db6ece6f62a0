#!/usr/bin/env python3
"""Does the LiDAR-camera calibration put the scan's depth edges on the image's edges?

  PYTHONPATH=build/release/python scripts/edge_alignment.py DRIVE [FRAMES]

DRIVE is anything `rgbl run` reads with a LiDAR (a KITTI odometry sequence, a KITTI raw drive),
opened through the rgbl module, so camera 0's calibration is the one the tracker uses. On FRAMES
frames spread over the drive (default 20) the scan's depth discontinuities (a return nearer than a
neighbour along its ring by > 0.5 m, weighted by the square root of the step) are projected into
camera 0 with the calibration turned by small angles about the camera's x (pitch) and y (yaw) axes
(the points turned, +x moves them up), and scored by the image gradient there (Sobel, blurred 1.5
px): the targetless check of Levinson and Thrun (RSS 2013). A grid of 0.1 deg over +-1 deg, then
0.025 deg around the best. Prints the best turn and the score against the calibration as given; the
sign convention is that of scripts/extrinsic_sensitivity.py. Needs the Python module
(build/release/python), python3-numpy and python3-opencv.
"""
import sys

import cv2
import numpy as np
import rgbl


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__)
    sequence = rgbl.open_sequence(argv[1], cameras=[True, False, False, False], depth=False)
    calibration = sequence.calibration.camera(0)
    K, T = calibration.camera.K, calibration.T_cam_lidar
    count = int(argv[2]) if len(argv) > 2 else 20
    frames = []
    for f in np.linspace(0, len(sequence) - 1, count).astype(int):
        frame = sequence.load(int(f), cameras=[True, False, False, False], depth=False)
        image = frame.images[0].astype(np.float32)
        edges = np.hypot(cv2.Sobel(image, cv2.CV_32F, 1, 0), cv2.Sobel(image, cv2.CV_32F, 0, 1))
        edges = cv2.GaussianBlur(edges, (0, 0), 1.5)
        edges /= edges.max()
        points = frame.scan[:, :3].astype(np.float64)
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
            uvw = (K @ q[front].T).T
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
