"""binbow.FeatureExtractor: the CLI's extractors on image files and numpy images."""
import copy
import pickle
import re
from pathlib import Path

import numpy as np
import pytest

import binbow
from conftest import SAMPLES, require_module, run_cli, sample_frames

FRAME = SAMPLES / "samples" / "1.jpg"


@pytest.fixture(scope="module")
def grey():
    cv2 = require_module("cv2", "python3-opencv")
    image = cv2.imread(str(FRAME), cv2.IMREAD_GRAYSCALE)
    assert image is not None, f"cannot read {FRAME}"
    return image


@pytest.mark.parametrize(
    "descriptor, code_size", [("orb", 32), ("brief", 32), ("akaze", 61), ("brisk", 64)]
)
def test_every_cli_extractor_with_its_code_size(descriptor, code_size):
    extractor = binbow.FeatureExtractor(descriptor)
    keypoints, descriptors = extractor.extract(FRAME)
    assert extractor.descriptor == descriptor and extractor.code_size == code_size
    assert keypoints.dtype == np.float32 and keypoints.shape == (len(keypoints), 6)
    assert descriptors.dtype == np.uint8 and descriptors.shape == (len(keypoints), code_size)
    assert len(keypoints) > 50
    x, y = keypoints[:, 0], keypoints[:, 1]
    assert (x >= 0).all() and (x < 512).all() and (y >= 0).all() and (y < 384).all()
    assert (keypoints[:, 5] == np.round(keypoints[:, 5])).all(), "octave is an integer"


@pytest.mark.parametrize("descriptor", ["orb", "brief", "akaze"])
def test_same_keypoint_count_as_the_cli(descriptor):
    printed = run_cli("features", "--descriptor", descriptor, FRAME).stdout
    count = int(re.search(r"^keypoints: (\d+)$", printed, re.M).group(1))
    keypoints, _ = binbow.FeatureExtractor(descriptor).extract(str(FRAME))
    assert len(keypoints) == count


def test_defaults_and_max_features():
    assert 300 < len(binbow.FeatureExtractor("orb").extract(FRAME)[0]) <= 1000
    assert len(binbow.FeatureExtractor("brief").extract(FRAME)[0]) == 300
    for descriptor in ("orb", "brief", "akaze", "brisk"):
        extractor = binbow.FeatureExtractor(descriptor, max_features=50)
        assert extractor.max_features == 50
        assert len(extractor.extract(FRAME)[0]) <= 50


def test_grey_array_and_path_agree(grey):
    extractor = binbow.FeatureExtractor()
    from_path = extractor.extract(Path(FRAME))
    from_array = extractor.extract(grey)
    np.testing.assert_array_equal(from_path[0], from_array[0])
    np.testing.assert_array_equal(from_path[1], from_array[1])


def test_bgr_and_non_contiguous_arrays(grey):
    bgr = np.ascontiguousarray(np.repeat(grey[:, :, None], 3, axis=2))
    extractor = binbow.FeatureExtractor()
    np.testing.assert_array_equal(extractor.extract(bgr)[1], extractor.extract(grey)[1])
    strided = grey[:, ::2]
    assert not strided.flags.c_contiguous
    np.testing.assert_array_equal(
        extractor.extract(strided)[1], extractor.extract(np.ascontiguousarray(strided))[1]
    )


def test_images_without_corners_give_empty_arrays():
    for descriptor in ("orb", "brief", "akaze", "brisk"):
        extractor = binbow.FeatureExtractor(descriptor)
        for image in (np.zeros((0, 0), np.uint8), np.full((64, 64), 128, np.uint8)):
            keypoints, descriptors = extractor.extract(image)
            assert keypoints.shape == (0, 6)
            assert descriptors.shape == (0, extractor.code_size)


def test_options_are_passed_on():
    few = binbow.FeatureExtractor("brief", fast_threshold=60, max_features=10_000)
    many = binbow.FeatureExtractor("brief", fast_threshold=5, max_features=10_000)
    assert len(few.extract(FRAME)[0]) < len(many.extract(FRAME)[0])
    suppressed = binbow.FeatureExtractor("brief", non_max_suppression=True, max_features=10_000)
    every = binbow.FeatureExtractor("brief", non_max_suppression=False, max_features=10_000)
    assert len(suppressed.extract(FRAME)[0]) < len(every.extract(FRAME)[0])
    one_level = binbow.FeatureExtractor("orb", levels=1, scale_factor=1.5, edge_threshold=19)
    assert set(one_level.extract(FRAME)[0][:, 5]) == {0.0}


def test_brief_pattern_file(tmp_path):
    pattern = tmp_path / "pattern.yml"
    tests = 16  # two bytes
    rng = np.random.default_rng(2)
    lines = ["%YAML:1.0"]
    for key in ("x1", "y1", "x2", "y2"):
        lines.append(f"{key}: [" + ", ".join(str(v) for v in rng.integers(-10, 11, tests)) + "]")
    pattern.write_text("\n".join(lines) + "\n")
    extractor = binbow.FeatureExtractor("brief", pattern=pattern)
    assert extractor.code_size == 2
    assert extractor.extract(FRAME)[1].shape[1] == 2
    with pytest.raises(OSError, match="missing.yml"):
        binbow.FeatureExtractor("brief", pattern=tmp_path / "missing.yml")


def test_strict_arguments(grey):
    extractor = binbow.FeatureExtractor()
    with pytest.raises(TypeError, match="float32"):
        extractor.extract(grey.astype(np.float32))
    with pytest.raises(TypeError, match="int16"):
        extractor.extract(grey.astype(np.int16))
    with pytest.raises(ValueError, match=r"\(384, 512, 2\)"):
        extractor.extract(np.zeros((384, 512, 2), np.uint8))
    with pytest.raises(ValueError, match=r"\(384,\)"):
        extractor.extract(np.zeros(384, np.uint8))
    with pytest.raises(TypeError, match="list"):
        extractor.extract([[1, 2], [3, 4]])
    with pytest.raises(OSError, match="missing.jpg"):
        extractor.extract("missing.jpg")
    with pytest.raises(ValueError, match="unknown descriptor 'sift'"):
        binbow.FeatureExtractor("sift")
    with pytest.raises(TypeError, match="threshold_typo"):
        binbow.FeatureExtractor("orb", threshold_typo=3)
    with pytest.raises(TypeError, match="pattern"):
        binbow.FeatureExtractor("orb", pattern="x.yml")
    with pytest.raises(TypeError, match="levels"):
        binbow.FeatureExtractor("akaze", levels=3)
    with pytest.raises(TypeError, match="max_features must be an int"):
        binbow.FeatureExtractor(max_features=100.0)
    with pytest.raises(ValueError, match="max_features"):
        binbow.FeatureExtractor(max_features=0)
    with pytest.raises(TypeError, match="non_max_suppression must be a bool"):
        binbow.FeatureExtractor("brief", non_max_suppression=1)
    with pytest.raises(ValueError, match="fast_threshold"):
        binbow.FeatureExtractor("orb", fast_threshold=300)
    with pytest.raises(ValueError, match="scale_factor"):
        binbow.FeatureExtractor("orb", scale_factor=1.0)


def test_repr_pickle_and_copy():
    extractor = binbow.FeatureExtractor("brief", max_features=200, fast_threshold=20)
    assert repr(extractor) == (
        'binbow.FeatureExtractor(descriptor="brief", max_features=200, fast_threshold=20)'
    )
    for clone in (pickle.loads(pickle.dumps(extractor)), copy.copy(extractor),
                  copy.deepcopy(extractor)):
        assert repr(clone) == repr(extractor)
        np.testing.assert_array_equal(clone.extract(FRAME)[1], extractor.extract(FRAME)[1])


def test_brief_keeps_border_corners_on_request():
    path = sample_frames()[0]
    inside = binbow.FeatureExtractor("brief", max_features=100_000)
    border = binbow.FeatureExtractor("brief", max_features=100_000, keep_border_corners=True)
    kept_inside, _ = inside.extract(path)
    kept_border, _ = border.extract(path)
    assert len(kept_border) > len(kept_inside)
    # Every corner whose tests stay inside the image is kept by both.
    assert {tuple(k[:2]) for k in kept_inside} <= {tuple(k[:2]) for k in kept_border}
    with pytest.raises(TypeError, match="keep_border_corners must be a bool"):
        binbow.FeatureExtractor("brief", keep_border_corners=1)
