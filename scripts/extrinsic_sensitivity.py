#!/usr/bin/env python3
"""How a drive's result depends on the LiDAR-camera rotation: the calibration turned by a small angle.

  scripts/extrinsic_sensitivity.py RGBL DRIVE AXIS DEG [DEG ...] [--features "1800 1900 2000 2100 2200"]
                                   [--settings FILE]

DRIVE is a KITTI raw drive folder (<date>/<date>_drive_NNNN_sync) or an odometry sequence folder
(.../sequences/NN, poses in ../../poses/NN.txt). For each angle a copy of the drive is made in a
temporary folder, every file a symlink except the LiDAR-to-camera calibration, whose rotation is
turned by DEG degrees about the camera's AXIS (x: pitch, y: yaw, z: roll; the points are turned, so
+x moves them up in the image). AXIS e instead raises every LiDAR point's elevation by DEG at its
range (a rotation about p x z; 0.205 deg is the HDL-64 vertical-angle correction that CT-ICP and
kiss-icp apply to KITTI's scans, after IMLS-SLAM): the copy's scans are rewritten, the calibration
kept. --settings adds that file's keys (lines of a settings YAML) to every run. RGBL
(build/release/bin/rgbl) tracks each copy once per ORB feature count, and the script prints per
angle the estimated path length over the truth's and the ATE, per sample and their mean, and the
mean end-point drift. Nothing in the data folder is written. Needs python3-numpy.
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


def link_except(src, dst, parts):
    """dst mirrors src as symlinks except the path parts[0]/parts[1]/...: the folders on it are made
    real and its last element is left out, for the caller to write."""
    os.makedirs(dst, exist_ok=True)
    for name in os.listdir(src):
        if parts and name == parts[0]:
            if len(parts) > 1:
                link_except(os.path.join(src, name), os.path.join(dst, name), parts[1:])
            continue
        os.symlink(os.path.join(src, name), os.path.join(dst, name))


def linked_copy(drive, root, odometry_path, raw_path):
    """A symlinked copy of the drive under root without one path, given relative to an odometry
    sequence folder (its poses two levels up) or to a raw drive's day folder (the calibration beside
    the drive). Returns (the copy to run, the source folder, the copy's folder, the path's parts)."""
    drive = os.path.abspath(drive)
    parent = os.path.dirname(drive)
    if os.path.exists(os.path.join(drive, 'calib.txt')):
        src, dst, parts = drive, os.path.join(root, 'sequences', os.path.basename(drive)), odometry_path
        run = dst
        poses = os.path.join(os.path.dirname(parent), 'poses')
        if os.path.isdir(poses):
            os.makedirs(root, exist_ok=True)
            os.symlink(poses, os.path.join(root, 'poses'))
    else:
        src, dst = parent, os.path.join(root, os.path.basename(parent))
        parts = [p if p != '{drive}' else os.path.basename(drive) for p in raw_path]
        run = os.path.join(dst, os.path.basename(drive))
    link_except(src, dst, parts)
    return run, src, dst, parts


def raise_elevation(xyz, deg):
    """Each point turned by deg about p x z: its elevation raised, its range and azimuth kept."""
    k = np.cross(xyz, np.array([0.0, 0.0, 1.0]))
    norm = np.linalg.norm(k, axis=1, keepdims=True)
    k /= np.where(norm > 0, norm, 1.0)
    a = np.radians(deg)
    return xyz * np.cos(a) + np.cross(k, xyz) * np.sin(a)  # k is orthogonal to p: Rodrigues' last term is 0


def elevated_copy(drive, deg, root):
    """A copy of the drive whose velodyne scans have every point's elevation raised by deg."""
    run, src, dst, parts = linked_copy(drive, root, ['velodyne'], ['{drive}', 'velodyne_points', 'data'])
    scans, scans_out = os.path.join(src, *parts), os.path.join(dst, *parts)
    os.makedirs(scans_out, exist_ok=True)
    for name in sorted(os.listdir(scans)):
        if not name.endswith('.bin'):
            continue
        p = np.fromfile(os.path.join(scans, name), dtype=np.float32).reshape(-1, 4).astype(np.float64)
        p[:, :3] = raise_elevation(p[:, :3], deg)
        p.astype(np.float32).tofile(os.path.join(scans_out, name))
    return run


def turned_copy(drive, axis, deg, root):
    """A copy of the drive with its LiDAR-to-camera rotation turned; returns the path to run."""
    if axis == 'e':
        return elevated_copy(drive, deg, root)
    R = rotation(axis, deg)
    run, src, dst, parts = linked_copy(drive, root, ['calib.txt'], ['calib_velo_to_cam.txt'])
    lines = []
    for line in open(os.path.join(src, *parts)):
        key = line.split(':', 1)[0]
        if key == 'Tr':  # odometry: T_cam0_velo, 3 x 4
            T = R @ np.array([float(v) for v in line.split()[1:]]).reshape(3, 4)
            line = 'Tr: ' + ' '.join('%.12e' % v for v in T.ravel()) + '\n'
        elif key == 'R':  # raw: rotation and translation on lines of their own
            Rv = R @ np.array([float(v) for v in line.split()[1:]]).reshape(3, 3)
            line = 'R: ' + ' '.join('%.12e' % v for v in Rv.ravel()) + '\n'
        elif key == 'T':
            t = R @ np.array([float(v) for v in line.split()[1:]])
            line = 'T: ' + ' '.join('%.12e' % v for v in t) + '\n'
        lines.append(line)
    open(os.path.join(dst, *parts), 'w').writelines(lines)
    return run


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
    settings = ''
    if '--settings' in argv:
        i = argv.index('--settings')
        settings = ''.join(l.rstrip('\n') + '\n' for l in open(argv[i + 1]) if not l.startswith('%YAML'))
        argv = argv[:i] + argv[i + 2:]
    if len(argv) < 5 or argv[3] not in ('x', 'y', 'z', 'e'):
        sys.exit(__doc__)
    rgbl, drive, axis = argv[1], argv[2], argv[3]
    with tempfile.TemporaryDirectory() as tmp:
        for deg in [float(v) for v in argv[4:]]:
            root = os.path.join(tmp, f'{axis}{deg:+g}')
            path = turned_copy(drive, axis, deg, root)
            ratios, ates, drifts = [], [], []
            for n in features:
                config = os.path.join(root, f'n{n}.yaml')
                open(config, 'w').write(f'%YAML:1.0\nORBextractor.nFeatures: {n}\n' + settings)
                out = os.path.join(root, f'run{n}')
                subprocess.run([rgbl, '-q', 'run', path, '--config', config, '--out', out],
                               check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                ratios.append(path_ratio(out))
                metrics = json.load(open(os.path.join(out, 'summary.json')))['metrics']
                ates.append(metrics['ate_rmse_m'])
                drifts.append(metrics['end_point_drift_percent'])
            print(f'{axis} {deg:+.3f} deg: path / truth ' + ' '.join(f'{r:.4f}' for r in ratios) +
                  f' (mean {np.mean(ratios):.4f}); ATE m ' + ' '.join(f'{a:.3f}' for a in ates) +
                  f' (mean {np.mean(ates):.3f}); end-point drift mean {np.mean(drifts):.2f} %', flush=True)


if __name__ == '__main__':
    main(sys.argv)
