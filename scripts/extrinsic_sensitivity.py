#!/usr/bin/env python3
"""How a drive's result depends on the LiDAR-camera rotation: the calibration turned by a small angle.

  scripts/extrinsic_sensitivity.py RGBL DRIVE AXIS DEG [DEG ...] [--features "1800 1900 2000 2100 2200"]

DRIVE is a KITTI raw drive folder (<date>/<date>_drive_NNNN_sync) or an odometry sequence folder
(.../sequences/NN, poses in ../../poses/NN.txt). For each angle a copy of the drive is made in a
temporary folder, every file a symlink except the LiDAR-to-camera calibration, whose rotation is
turned by DEG degrees about the camera's AXIS (x: pitch, y: yaw, z: roll; the points are turned, so
+x moves them up in the image). RGBL (build/release/bin/rgbl) tracks it once per ORB feature count, and
the script prints per angle the estimated path length over the truth's and the ATE, per sample and
their mean. Nothing in the data folder is written. Needs python3-numpy.
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np


def rotation(axis, deg):
    a = np.radians(deg)
    c, s = np.cos(a), np.sin(a)
    return {'x': np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
            'y': np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
            'z': np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]


def link_all(src, dst, skip):
    os.makedirs(dst, exist_ok=True)
    for name in os.listdir(src):
        if name not in skip:
            os.symlink(os.path.join(src, name), os.path.join(dst, name))


def turned_copy(drive, axis, deg, root):
    """A copy of the drive with its LiDAR-to-camera rotation turned; returns the path to run."""
    drive = os.path.abspath(drive)
    R = rotation(axis, deg)
    parent = os.path.dirname(drive)
    if os.path.exists(os.path.join(drive, 'calib.txt')):  # odometry: Tr in calib.txt, poses two levels up
        seq = os.path.basename(drive)
        out = os.path.join(root, 'sequences', seq)
        link_all(drive, out, {'calib.txt'})
        poses = os.path.join(os.path.dirname(parent), 'poses')
        if os.path.isdir(poses):
            os.symlink(poses, os.path.join(root, 'poses'))
        lines = []
        for line in open(os.path.join(drive, 'calib.txt')):
            if line.startswith('Tr:'):
                T = np.array([float(v) for v in line.split()[1:]]).reshape(3, 4)
                T = R @ T
                line = 'Tr: ' + ' '.join('%.12e' % v for v in T.ravel()) + '\n'
            lines.append(line)
        open(os.path.join(out, 'calib.txt'), 'w').writelines(lines)
        return out
    # raw: <date>/calib_velo_to_cam.txt beside the drive folder
    day = os.path.join(root, os.path.basename(parent))
    link_all(parent, day, {'calib_velo_to_cam.txt'})
    lines = []
    for line in open(os.path.join(parent, 'calib_velo_to_cam.txt')):
        if line.startswith('R:'):
            Rv = R @ np.array([float(v) for v in line.split()[1:]]).reshape(3, 3)
            line = 'R: ' + ' '.join('%.12e' % v for v in Rv.ravel()) + '\n'
        elif line.startswith('T:'):
            t = R @ np.array([float(v) for v in line.split()[1:]])
            line = 'T: ' + ' '.join('%.12e' % v for v in t) + '\n'
        lines.append(line)
    open(os.path.join(day, 'calib_velo_to_cam.txt'), 'w').writelines(lines)
    return os.path.join(day, os.path.basename(drive))


def path_ratio(run):
    est = np.loadtxt(os.path.join(run, 'trajectory_kitti.txt')).reshape(-1, 3, 4)[:, :, 3]
    gt = np.loadtxt(os.path.join(run, 'ground_truth_kitti.txt')).reshape(-1, 3, 4)[:, :, 3]
    n = min(len(est), len(gt))
    return (np.linalg.norm(np.diff(est[:n], axis=0), axis=1).sum() /
            np.linalg.norm(np.diff(gt[:n], axis=0), axis=1).sum())


def main(argv):
    features = [1800, 1900, 2000, 2100, 2200]
    if '--features' in argv:
        i = argv.index('--features')
        features = [int(v) for v in argv[i + 1].split()]
        argv = argv[:i] + argv[i + 2:]
    if len(argv) < 5 or argv[3] not in ('x', 'y', 'z'):
        sys.exit(__doc__)
    rgbl, drive, axis = argv[1], argv[2], argv[3]
    with tempfile.TemporaryDirectory() as tmp:
        for deg in [float(v) for v in argv[4:]]:
            root = os.path.join(tmp, f'{axis}{deg:+g}')
            path = turned_copy(drive, axis, deg, root)
            ratios, ates = [], []
            for n in features:
                config = os.path.join(root, f'n{n}.yaml')
                open(config, 'w').write(f'%YAML:1.0\nORBextractor.nFeatures: {n}\n')
                out = os.path.join(root, f'run{n}')
                subprocess.run([rgbl, '-q', 'run', path, '--config', config, '--out', out],
                               check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                ratios.append(path_ratio(out))
                ates.append(json.load(open(os.path.join(out, 'summary.json')))['metrics']['ate_rmse_m'])
            print(f'{axis} {deg:+.2f} deg: path / truth ' + ' '.join(f'{r:.4f}' for r in ratios) +
                  f' (mean {np.mean(ratios):.4f}); ATE m ' + ' '.join(f'{a:.3f}' for a in ates) +
                  f' (mean {np.mean(ates):.3f})', flush=True)


if __name__ == '__main__':
    main(sys.argv)
