"""The ORB extractor: keypoints and descriptors without copies, deterministic."""

import numpy as np
import pytest

import rgbl


@pytest.fixture(scope="module")
def image(short_street):
    return rgbl.open_sequence(short_street.sequence_dir).load(0).images[0]


def test_extraction_on_a_synthetic_image(image):
    options = rgbl.OrbOptions()
    options.num_features = 500
    extractor = rgbl.OrbExtractor(options)
    keypoints, descriptors = extractor.extract(image)
    n = len(keypoints)
    assert 300 < n <= 500
    assert keypoints.dtype.names == ("x", "y", "angle", "response", "size", "level")
    assert descriptors.shape == (n, 32) and descriptors.dtype == np.uint8
    assert (keypoints["x"] >= 0).all() and (keypoints["x"] < image.shape[1]).all()
    assert set(np.unique(keypoints["level"])) <= set(range(8))
    assert (keypoints["angle"] >= 0).all() and (keypoints["angle"] < 360).all()
    # the C++ vectors are the arrays' buffers
    assert not keypoints.flags.owndata and not descriptors.flags.owndata
    again_k, again_d = extractor.extract(image)
    assert np.array_equal(again_k, keypoints) and np.array_equal(again_d, descriptors)
    assert rgbl.hamming_distance(descriptors[0], descriptors[0]) == 0
    assert rgbl.hamming_distance(descriptors[0], np.bitwise_not(descriptors[0])) == 256


def test_colour_images_are_refused(image):
    with pytest.raises(TypeError, match="grey"):
        rgbl.OrbExtractor().extract(np.dstack([image] * 3))


def test_bad_options_name_the_key():
    options = rgbl.OrbOptions()
    options.scale_factor = 0.5
    with pytest.raises(rgbl.ConfigError):
        rgbl.OrbExtractor(options)
