"""Errors that describe the input in Python's terms, and the C++ API's features in Python."""
import copy
import pickle

import numpy as np
import pytest

import binbow
from conftest import SAMPLES, require_module, sample_frames

FRAME = SAMPLES / "samples" / "1.jpg"


def test_query_takes_descriptors_and_never_prints_them(database, images):
    assert database.query(images[3], 3) == database.query(database.vocabulary.transform(images[3]), 3)
    assert database.query(None) == []
    big = np.full((5000, 32), 0xAB, np.uint8)
    for call, error in [
        (lambda: database.query(big.astype(np.float32)), TypeError),
        (lambda: database.query(big[:, :16]), ValueError),
        (lambda: database.query(big[None]), ValueError),
        (lambda: database.query(big, -1), ValueError),
        (lambda: database.query(big, True), TypeError),
        (lambda: database.query(big, 3, -2), ValueError),
        (lambda: database.query(big.tolist()), TypeError),
        (lambda: database.add(big, label=7), TypeError),
        (lambda: database.add_bow(database.vocabulary.transform(big), label=7), TypeError),
    ]:
        with pytest.raises(error) as raised:
            call()
        message = str(raised.value)
        assert "171" not in message and "0xab" not in message.lower(), message
        assert len(message) < 400, message


def test_the_descriptors_are_described_by_dtype_and_shape(database):
    with pytest.raises(TypeError, match=r"descriptors must be a numpy uint8 array, got dtype float32"):
        database.query(np.zeros((3, 32), np.float32))
    with pytest.raises(ValueError, match=r"got shape \(1, 3, 32\)"):
        database.query(np.zeros((1, 3, 32), np.uint8))


@pytest.mark.parametrize("make", [
    lambda: np.lib.stride_tricks.as_strided(np.zeros(32, np.uint8), (10**9, 32), (0, 1)),
    lambda: np.broadcast_to(np.zeros(32, np.uint8), (10**9, 32)),
], ids=["as_strided", "broadcast_to"])
def test_huge_strided_views_are_refused_without_copying(database, vocabulary, make):
    view = make()
    for call in (vocabulary.transform, database.add, database.query, vocabulary.quantize):
        with pytest.raises(binbow.Error, match=r"descriptors \(dtype uint8, shape \(1000000000, 32\)\) "
                                             r"is not C-contiguous and too large to copy"):
            call(view)
    assert len(database) == 12


def test_small_strided_views_are_still_copied(vocabulary, images):
    row = images[0][:1]
    view = np.broadcast_to(row, (5, 32))
    assert vocabulary.transform(view) == vocabulary.transform(np.repeat(row, 5, axis=0))


def test_load_errors_name_the_python_keyword(tmp_path):
    unknown = tmp_path / "mystery.dat"
    unknown.write_bytes(b"\x00\x01nothing binbow knows" * 8)
    with pytest.raises(OSError) as raised:
        binbow.Vocabulary.load(unknown)
    assert "format=" in str(raised.value)
    assert "--from" not in str(raised.value)


# FeatureExtractor

@pytest.fixture(scope="module")
def bgr():
    cv2 = require_module("cv2", "python3-opencv")
    image = cv2.imread(str(FRAME), cv2.IMREAD_COLOR)
    assert image is not None, f"cannot read {FRAME}"
    return image


def test_bgra_images_are_converted_as_opencv_does(bgr):
    cv2 = require_module("cv2", "python3-opencv")
    bgra = cv2.cvtColor(bgr, cv2.COLOR_BGR2BGRA)
    extractor = binbow.FeatureExtractor("orb")
    keypoints, descriptors = extractor.extract(bgra)
    expected = extractor.extract(cv2.cvtColor(bgra, cv2.COLOR_BGRA2GRAY))
    assert len(descriptors) > 100
    assert np.array_equal(keypoints, expected[0]) and np.array_equal(descriptors, expected[1])


def test_read_only_images_are_accepted(bgr):
    image = bgr.copy()
    image.flags.writeable = False
    extractor = binbow.FeatureExtractor()
    assert np.array_equal(extractor.extract(image)[1], extractor.extract(bgr.copy())[1])


def test_arrays_have_the_pixel_limit_of_files(tmp_path):
    assert binbow.FeatureExtractor().max_image_pixels == 100_000_000
    small = binbow.FeatureExtractor(max_image_pixels=1000)
    with pytest.raises(ValueError, match=r"image of shape \(40, 30\) has 1200 pixels, more than "
                                         r"the limit of 1000"):
        small.extract(np.zeros((40, 30), np.uint8))
    with pytest.raises(OSError, match="limit of 1000"):
        small.extract(FRAME)
    small.extract(np.zeros((20, 50), np.uint8))  # 1000 pixels: at the limit
    # A huge image is refused from its shape, before any pixel is read or copied.
    huge = np.lib.stride_tricks.as_strided(np.zeros(1, np.uint8), (200_000, 1_000), (0, 0))
    with pytest.raises(ValueError, match="more than the limit of 100000000"):
        binbow.FeatureExtractor().extract(huge)
    with pytest.raises(ValueError, match="max_image_pixels"):
        binbow.FeatureExtractor(max_image_pixels=0)
    with pytest.raises(TypeError, match="max_image_pixels"):
        binbow.FeatureExtractor(max_image_pixels=1.5)


def test_the_limit_is_kept_by_repr_and_pickle():
    extractor = binbow.FeatureExtractor("brief", max_image_pixels=5000)
    assert repr(extractor) == 'binbow.FeatureExtractor(descriptor="brief", max_image_pixels=5000)'
    assert pickle.loads(pickle.dumps(extractor)).max_image_pixels == 5000
    assert repr(binbow.FeatureExtractor()) == 'binbow.FeatureExtractor(descriptor="orb")'


def test_descriptor_names_are_case_insensitive():
    for name in ("ORB", "Orb", "BRIEF", "AKAZE"):
        extractor = binbow.FeatureExtractor(name)
        assert extractor.descriptor == name.lower()
    with pytest.raises(ValueError, match="unknown descriptor 'sift'"):
        binbow.FeatureExtractor("SIFT")


# LoopDetector

@pytest.fixture(scope="module")
def features():
    extractor = binbow.FeatureExtractor()
    return [extractor.extract(path) for path in sample_frames()[:30]]


def test_loop_detector_repr_and_labels(features):
    detector = binbow.LoopDetector(binbow.Vocabulary.default("orb"))
    assert repr(detector).startswith("<binbow.LoopDetector with 0 images, vocabulary ")
    for keypoints, descriptors in features[:3]:
        detector.process(keypoints, descriptors)
    detector.set_label(1, "1.jpg")
    assert detector.label(1) == "1.jpg" and detector.label(0) is None
    detector.set_label(1, "")
    assert detector.label(1) is None
    with pytest.raises(ValueError):
        detector.label(3)
    with pytest.raises(TypeError, match="frame must be an int"):
        detector.set_label("1", "x")
    detector.forget(2)
    assert repr(detector).startswith("<binbow.LoopDetector with 3 images (1 forgotten)")
    online = binbow.LoopDetector.online("orb")
    assert repr(online) == "<binbow.LoopDetector with 0 images, online vocabulary of 0 words>"


@pytest.mark.parametrize("online", [False, True], ids=["fixed", "online"])
@pytest.mark.parametrize("clone", [pickle.loads, None], ids=["pickle", "deepcopy"])
def test_loop_detector_pickles_and_continues_identically(features, online, clone):
    def make():
        if online:
            return binbow.LoopDetector.online("orb")
        return binbow.LoopDetector(binbow.Vocabulary.default("orb"))

    original = make()
    for keypoints, descriptors in features[:20]:
        original.process(keypoints, descriptors)
    original.set_label(4, "four")
    restored = clone(pickle.dumps(original)) if clone else copy.deepcopy(original)
    assert len(restored) == 20 and restored.label(4) == "four"
    assert restored.is_online == online
    for keypoints, descriptors in features[20:]:
        a = original.process(keypoints, descriptors).__getstate__()
        b = restored.process(keypoints, descriptors).__getstate__()
        assert a[:18] + a[19:] == b[:18] + b[19:]  # all but the stage times


def test_a_damaged_pickled_loop_detector_is_an_error():
    detector = binbow.LoopDetector(binbow.Vocabulary.default("orb"))
    data, vocabulary = detector.__getstate__()
    damaged = bytearray(data)
    damaged[len(damaged) // 2] ^= 0xFF
    with pytest.raises(OSError, match="pickled binbow.LoopDetector"):
        binbow.LoopDetector.__new__(binbow.LoopDetector).__setstate__((bytes(damaged), vocabulary))
    with pytest.raises(ValueError, match="invalid pickled binbow.LoopDetector"):
        binbow.LoopDetector.__new__(binbow.LoopDetector).__setstate__((data,))


def test_detect_loops_takes_the_extractor_the_vocabulary_records():
    brief = binbow.Vocabulary.default("brief")
    results = binbow.detect_loops(sample_frames()[:3], vocabulary=brief)
    assert results.descriptor == "brief" and len(results) == 3
    with pytest.raises(ValueError, match="trained on brief descriptors, not orb"):
        binbow.detect_loops(sample_frames()[:3], vocabulary=brief, descriptor="orb")
