"""Cameras and the LiDAR projection on exactly known points."""

import numpy as np
import pytest

import rgbl


def test_projection_of_known_points(camera):
    px = camera.project(np.array([[1.0, 2.0, 10.0], [0.0, 0.0, -1.0], [100.0, 0.0, 1.0]]))
    assert px.shape == (3, 2)
    assert px[0] == pytest.approx([100 * 0.1 + 50, 100 * 0.2 + 30], abs=1e-12)
    assert np.isnan(px[1]).all()  # behind the camera
    assert np.isnan(px[2]).all()  # outside the image
    assert camera.project([1.0, 2.0, 10.0]) == pytest.approx([60.0, 50.0])
    assert camera.unproject((60.0, 50.0), 10.0) == pytest.approx((1.0, 2.0, 10.0))
    assert np.array_equal(camera.K, [[100, 0, 50], [0, 100, 30], [0, 0, 1]])


def test_project_to_depth_z_buffers_a_scan(camera):
    # LiDAR frame = camera frame; two points on one pixel: the nearer wins
    calibration = rgbl.CameraCalibration(camera)
    scan = np.array([[1.0, 2.0, 10.0, 0.5], [2.0, 4.0, 20.0, 0.5], [0.0, 0.0, 6.0, 0.1], [0, 0, 3.0, 0]], np.float32)
    depth = rgbl.project_to_depth(scan, calibration)
    assert depth.shape == (61, 101) and depth.dtype == np.float32
    assert depth[50, 60] == np.float32(10.0)
    assert depth[30, 50] == np.float32(6.0)
    assert np.count_nonzero(depth) == 2  # the point at 3 m is nearer than min_depth 5 m
    assert np.count_nonzero(rgbl.project_to_depth(scan, calibration, min_depth=1.0)) == 2  # 3 m hides 6 m
    assert rgbl.project_to_depth(scan, calibration, min_depth=1.0)[30, 50] == np.float32(3.0)
    # the same through an explicit 3 x 4 projection and size
    same = rgbl.project_to_depth(scan, calibration.P_img_lidar, 101, 61)
    assert np.array_equal(same, depth)


def test_extrinsics_move_the_points(camera):
    T = np.eye(4)
    T[0, 3] = 1.0  # the LiDAR origin is 1 m right of the camera
    calibration = rgbl.CameraCalibration(camera, T_cam_lidar=T)
    depth = rgbl.project_to_depth(np.array([[0.0, 0.0, 10.0, 0.0]], np.float32), calibration)
    assert depth[30, 60] == np.float32(10.0)
    assert np.array_equal(calibration.T_cam_lidar, T)


def test_strided_and_float64_scans_give_the_same_depth(camera):
    calibration = rgbl.CameraCalibration(camera)
    rng = np.random.default_rng(1)
    scan = np.column_stack([rng.uniform(-5, 5, 500), rng.uniform(-3, 3, 500), rng.uniform(6, 50, 500),
                            np.zeros(500)]).astype(np.float32)
    reference = rgbl.project_to_depth(scan, calibration)
    assert np.count_nonzero(reference) > 300
    assert np.array_equal(rgbl.project_to_depth(np.asfortranarray(scan), calibration), reference)
    wide = np.zeros((500, 8), np.float32)
    wide[:, ::2] = scan
    assert np.array_equal(rgbl.project_to_depth(wide[:, ::2], calibration), reference)


def test_kitti_calibration_file(tmp_path):
    P0 = "P0: 700 0 600 0 0 700 180 0 0 0 1 0"
    P1 = "P1: 700 0 600 -378 0 700 180 0 0 0 1 0"  # baseline 378 / 700 = 0.54 m
    tr = "Tr: 0 -1 0 0 0 0 -1 -0.08 1 0 0 -0.27"
    (tmp_path / "calib.txt").write_text("\n".join([P0, P1, P0.replace("P0", "P2"), P0.replace("P0", "P3"), tr]) + "\n")
    k = rgbl.read_kitti_calibration(tmp_path / "calib.txt", 1226, 370)
    assert k.baseline(0, 1) == pytest.approx(0.54)
    cam1 = k.camera(1)
    assert cam1.camera.fx == 700 and cam1.camera.width == 1226
    assert cam1.T_cam_cam0[0, 3] == pytest.approx(-0.54)
    assert k.T_cam0_lidar[1, 3] == pytest.approx(-0.08)
    # a LiDAR point 10 m ahead (x forward) is 10 m deep in cam0, 0.27 m further in z
    p = k.camera(0).P_img_lidar @ np.array([10.0, 0.0, 0.0, 1.0])
    assert p[2] == pytest.approx(10.0 - 0.27)
