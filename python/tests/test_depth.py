"""Depth kernels, every registered depth source and the depth metrics on exactly known data."""

import numpy as np
import pytest

import rgbl


def one_point(value=10.0, shape=(21, 31), at=(10, 15)):
    sparse = np.zeros(shape, np.float32)
    sparse[at] = value
    return sparse


@pytest.mark.parametrize("kernel,size,cells", [("diamond", 5, 13), ("rectangle", 5, 25), ("cross", 5, 9),
                                               ("diamond", 7, 25), ("rectangle", 3, 9)])
def test_dilation_of_one_point_fills_the_kernel(kernel, size, cells):
    dense = rgbl.dilate_depth(one_point(), kernel=kernel, size=size)
    assert dense.dtype == np.float32 and dense.shape == (21, 31)
    assert np.count_nonzero(dense) == cells
    assert set(np.unique(dense[dense > 0])) == {np.float32(10.0)}
    r = size // 2
    assert dense[10, 15 - r] == 10.0 and dense[10 - r, 15] == 10.0  # the arms reach `radius`
    assert dense[10, 15 - r - 1] == 0.0


def test_dilation_nearest_depth_wins():
    sparse = one_point(20.0)
    sparse[10, 17] = 8.0
    dense = rgbl.dilate_depth(sparse)
    assert dense[10, 16] == np.float32(8.0)  # both under the kernel: the nearer
    assert dense[10, 13] == np.float32(20.0)  # only the far one reaches
    assert dense[10, 15] == np.float32(8.0)


def test_dilation_reads_a_cropped_view_in_place():
    big = np.zeros((40, 60), np.float32)
    big[15, 25] = 10.0
    crop = big[5:26, 10:41]  # strided rows: viewed, not copied
    assert not crop.flags.c_contiguous
    assert np.array_equal(rgbl.dilate_depth(crop), rgbl.dilate_depth(one_point()))


def test_ip_basic_fills_more_than_dilation():
    rng = np.random.default_rng(3)
    sparse = np.zeros((60, 80), np.float32)
    idx = rng.choice(sparse.size, 300, replace=False)
    sparse.flat[idx] = 12.0
    dilated = rgbl.dilate_depth(sparse)
    for mode in ("fast", "multiscale"):
        dense = rgbl.ip_basic(sparse, mode=mode)
        assert dense.shape == sparse.shape
        assert rgbl.depth_density(dense) > rgbl.depth_density(dilated)
        assert np.abs(dense[dense > 0] - 12.0).max() < 1e-3  # a constant scene stays constant
    assert rgbl.depth_density(sparse) == pytest.approx(300 / 4800)
    with pytest.raises(rgbl.ConfigError):
        rgbl.ip_basic(sparse, mode="slow")


def test_every_registered_source_is_created_by_name(camera):
    calibration = rgbl.CameraCalibration(camera)
    names = rgbl.depth_source_names()
    assert names == ["lidar", "precomputed", "rgbd", "stereo", "stereo_sparse"]
    for spec in ["lidar", "lidar:dilated", "lidar:ipbasic", "lidar:ipbasic-multiscale", "lidar:cross7", "rgbd",
                 "stereo_sparse"]:
        source = rgbl.make_depth_source(spec, calibration, stereo_baseline=0.5)
        assert source.name == spec.split(":")[0]
    # dense stereo needs images wider than its 128 px disparity range: refused on this 101 px camera
    with pytest.raises(rgbl.ConfigError, match="wider than its disparity range"):
        rgbl.make_depth_source("stereo", calibration, stereo_baseline=0.5)
    wide = rgbl.CameraCalibration(rgbl.PinholeCamera(fx=100.0, fy=100.0, cx=150.0, cy=30.0, width=301, height=61))
    assert rgbl.make_depth_source("stereo", wide, stereo_baseline=0.5).name == "stereo"
    assert rgbl.depth_source_needs("lidar").scan
    assert rgbl.depth_source_needs("stereo").right_image
    assert rgbl.depth_source_needs("rgbd").depth_image


def test_lidar_source_samples_the_projected_point(camera):
    source = rgbl.make_depth_source("lidar:dilated", rgbl.CameraCalibration(camera))
    image = np.zeros((61, 101), np.uint8)
    source.prepare(image, np.array([[1.0, 2.0, 10.0, 0.0]], np.float32))
    out = source.sample(np.array([[60, 50], [61, 50], [60, 52], [10, 10]], np.float32))
    assert out.shape == (4, 4) and out.dtype == np.float32
    assert out[:, 0] == pytest.approx([10.0, 10.0, 10.0, 0.0])
    assert out[1, 1] == pytest.approx(1.0)  # one pixel from the measurement
    dense = source.dense_depth()
    assert np.array_equal(dense, rgbl.dilate_depth(rgbl.project_to_depth(
        np.array([[1.0, 2.0, 10.0, 0.0]], np.float32), rgbl.CameraCalibration(camera))))


def test_rgbd_source_reads_a_depth_image(camera):
    source = rgbl.make_depth_source("rgbd", rgbl.CameraCalibration(camera))
    depth = np.full((61, 101), 2.5, np.float32)
    source.prepare(np.zeros((61, 101), np.uint8), depth_image=depth)
    assert source.sample(np.array([[40.0, 20.0]], np.float32))[0, 0] == np.float32(2.5)
    with pytest.raises(rgbl.ConfigError, match="depth_image"):
        source.prepare(np.zeros((61, 101), np.uint8))


def test_depth_metrics_of_a_known_offset():
    truth = np.zeros((10, 10), np.float32)
    truth[:5] = 10.0
    prediction = np.where(truth > 0, truth + 1.0, 0).astype(np.float32)
    prediction[0, 0] = 0.0  # one pixel not predicted
    errors = rgbl.evaluate_depth(prediction, truth)
    assert errors.count == 49
    assert errors.coverage == pytest.approx(49 / 50)
    assert errors.mae == pytest.approx(1.0) and errors.rmse == pytest.approx(1.0)
    assert errors.imae == pytest.approx(1000 * (1 / 10 - 1 / 11))
    pooled = rgbl.DepthErrorAccumulator()
    pooled.add(prediction, truth)
    pooled.add(truth, truth)
    assert pooled.result().count == 99 and pooled.result().mae == pytest.approx(49 / 99)


def test_depth_png_round_trip(tmp_path):
    depth = np.array([[0.0, 1.5, 10.25]], np.float32)
    rgbl.write_depth_png(tmp_path / "d.png", depth)
    assert np.array_equal(rgbl.read_depth_png(tmp_path / "d.png"), depth)  # multiples of 1/256 survive


def test_lidar_source_plane_fit_between_rings():
    # A road 15 m below a camera looking along it, scanned by four rings: inverse depth is affine in the
    # row (1/z = (v - cy) / (fy h)), so the plane fit between two rings is exact, while the surface mean
    # reads the nearer ring alone.
    camera = rgbl.PinholeCamera(fx=100.0, fy=100.0, cx=50.0, cy=30.0, width=101, height=201)
    calibration = rgbl.CameraCalibration(camera)
    points = []
    for v in (177, 180, 183, 186):
        z = 1500.0 / (v - 30)
        points += [[(u - 50) * z / 100.0, 15.0, z, 0.0] for u in range(40, 61)]
    scan = np.array(points, np.float32)
    keypoint = np.array([[50.0, 181.4]], np.float32)
    exact = 1500.0 / (181.4 - 30.0)
    image = np.zeros((201, 101), np.uint8)
    mean = rgbl.make_lidar_source(calibration, surface_fit_window_deg=0.0)
    mean.prepare(image, scan)
    assert mean.sample(keypoint)[0, 0] == pytest.approx(1500.0 / 153.0, rel=1e-5)  # ring 183's depth
    fit = rgbl.make_lidar_source(calibration, surface_fit_window_deg=2.5)  # 4 rows either side
    fit.prepare(image, scan)
    assert fit.sample(keypoint)[0, 0] == pytest.approx(exact, rel=1e-5)
    with pytest.raises(rgbl.ConfigError, match="surface_fit_window_deg"):
        rgbl.make_lidar_source(calibration, surface_fit_window_deg=-1.0)
    with pytest.raises(rgbl.ConfigError, match="surface_step_px"):
        rgbl.make_lidar_source(calibration, surface_step_px=0)
