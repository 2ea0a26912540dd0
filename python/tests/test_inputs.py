"""Descriptors are checked, never silently converted, wherever they are taken."""
import numpy as np
import pytest

import binbow


# Every entry point that takes the descriptors of one image.
def _transform(voc, d):
    return voc.transform(d)


def _transform_with_features(voc, d):
    return voc.transform_with_features(d)[0]


def _quantize(voc, d):
    return voc.quantize(d)


def _add(voc, d):
    return binbow.Database(voc).add(d)


def _build(voc, d):
    return binbow.Vocabulary.build([d], branching=2, levels=1)


ENTRY_POINTS = [_transform, _transform_with_features, _quantize, _add, _build]
ids = [f.__name__.lstrip("_") for f in ENTRY_POINTS]


@pytest.mark.parametrize("call", ENTRY_POINTS, ids=ids)
@pytest.mark.parametrize(
    "bad, dtype_name",
    [
        (np.full((1, 32), 300.7), "float64"),  # was quantised as byte 44
        (np.full((1, 32), -1), "int64"),  # was byte 255
        (np.zeros((4, 32), np.float32), "float32"),  # SIFT: was a "1024-bit" vocabulary
        (np.zeros((4, 32), np.int8), "int8"),
        (np.zeros((4, 32), np.uint16), "uint16"),
        (np.zeros((4, 32), bool), "bool"),
    ],
)
def test_other_dtypes_are_type_errors_naming_the_dtype(vocabulary, call, bad, dtype_name):
    with pytest.raises(TypeError, match=f"uint8.*{dtype_name}"):
        call(vocabulary, bad)


@pytest.mark.parametrize("call", ENTRY_POINTS, ids=ids)
def test_non_arrays_are_type_errors(vocabulary, call):
    with pytest.raises(TypeError, match="list"):
        call(vocabulary, [[0] * 32])
    with pytest.raises(TypeError, match="bytes"):
        call(vocabulary, bytes(32))


@pytest.mark.parametrize("call", ENTRY_POINTS, ids=ids)
@pytest.mark.parametrize("shape", [(32,), (2, 2, 32), ()])
def test_other_shapes_are_value_errors(vocabulary, call, shape):
    with pytest.raises(ValueError, match=r"2-D.*shape \("):
        call(vocabulary, np.zeros(shape, np.uint8))


@pytest.mark.parametrize("call", [_transform, _transform_with_features, _quantize, _add],
                         ids=ids[:4])
@pytest.mark.parametrize("rows", [0, 3])
def test_the_code_size_must_be_the_vocabulary_s(vocabulary, call, rows):
    with pytest.raises(ValueError, match="64 bytes .* 32 bytes"):
        call(vocabulary, np.zeros((rows, 64), np.uint8))


@pytest.mark.parametrize("call", ENTRY_POINTS[:4], ids=ids[:4])
def test_none_is_an_image_without_features(vocabulary, call):
    result = call(vocabulary, None)
    expected = call(vocabulary, np.empty((0, 32), np.uint8))
    if isinstance(result, np.ndarray):
        assert np.array_equal(result, expected) and len(result) == 0
    else:
        assert result == expected


# Vocabulary.build with None among real images: test_vocabulary.py.
def test_build_from_none_only_says_there_is_nothing_to_train_on():
    with pytest.raises(ValueError, match="no descriptors|no training|empty"):
        binbow.Vocabulary.build([None, None], branching=2, levels=1)


def test_non_contiguous_arrays_are_copied_not_misread(vocabulary, images):
    image = images[0]
    # Every other row, and a Fortran-ordered copy: same descriptors, other strides.
    strided = np.repeat(image, 2, axis=0)[::2]
    fortran = np.asfortranarray(image)
    assert not strided.flags.c_contiguous and not fortran.flags.c_contiguous
    expected = vocabulary.quantize(image)
    assert np.array_equal(vocabulary.quantize(strided), expected)
    assert np.array_equal(vocabulary.quantize(fortran), expected)
    assert vocabulary.transform(strided) == vocabulary.transform(image)
    db = binbow.Database(vocabulary)
    db.add(fortran)
    assert db.query(vocabulary.transform(image), 1)[0][1] == pytest.approx(1.0)
    # A column slice is 2-D uint8 but of another code size: refused, not padded.
    with pytest.raises(ValueError, match="16 bytes"):
        vocabulary.quantize(image[:, :16])


def test_build_names_the_bad_image(images):
    with pytest.raises(TypeError, match=r"images\[2\].*float32"):
        binbow.Vocabulary.build([images[0], images[1], images[2].astype(np.float32)])
    with pytest.raises(TypeError, match="list of descriptor arrays"):
        binbow.Vocabulary.build(images[0])
    with pytest.raises(ValueError, match="mixed descriptor sizes"):
        binbow.Vocabulary.build([images[0], np.zeros((5, 64), np.uint8)], branching=2, levels=1)


def test_hamming_is_strict_too():
    a = np.zeros(32, np.uint8)
    with pytest.raises(TypeError, match="float64"):
        binbow.hamming(a, np.zeros(32))
    with pytest.raises(ValueError, match="same length"):
        binbow.hamming(a, np.zeros(16, np.uint8))
    with pytest.raises(ValueError):
        binbow.hamming(np.zeros((1, 32), np.uint8), np.zeros((1, 32), np.uint8))
    assert binbow.hamming(a, np.full(32, 255, np.uint8)[::1]) == 256
    assert binbow.hamming(np.zeros(64, np.uint8)[::2], np.full(32, 1, np.uint8)) == 32


def test_bow_vector_words_must_be_word_ids():
    bow = binbow.BowVector(np.array([1, 5, 9]), np.array([0.2, 0.3, 0.5]))
    assert bow.words.dtype == np.uint32 and bow.values.dtype == np.float32
    with pytest.raises(ValueError, match="word id"):
        binbow.BowVector(np.array([-1, 5]), np.array([0.5, 0.5]))
    with pytest.raises(ValueError, match="word id"):
        binbow.BowVector(np.array([2**32]), np.array([1.0]))
    with pytest.raises(TypeError, match="integer"):
        binbow.BowVector(np.array([1.5]), np.array([1.0]))
    with pytest.raises(ValueError, match="same length"):
        binbow.BowVector(np.array([1, 2]), np.array([1.0]))
    with pytest.raises(ValueError, match="increasing"):
        binbow.BowVector(np.array([5, 1]), np.array([0.5, 0.5]))


# Past 2**63 pybind11's own conversion raised RuntimeError "Unable to cast", and
# for a parameter of a C++ integer type a TypeError listing every argument.
@pytest.mark.parametrize("value", [2**63, 2**64, -(2**63) - 1, 10**5000],
                         ids=["2**63", "2**64", "-2**63-1", "10**5000"])
def test_ints_of_any_size_are_value_errors_naming_the_argument(vocabulary, images, database,
                                                                value):
    image = images[0]
    calls = {
        "levels_up": lambda: vocabulary.transform_with_features(image, value),
        "threads": lambda: binbow.Vocabulary.build([image, image], threads=value),
        "branching": lambda: binbow.Vocabulary.build([image, image], branching=value),
        "max_iterations": lambda: binbow.Vocabulary.build([image, image], max_iterations=value),
        "max_features": lambda: binbow.FeatureExtractor("orb", value),
        "fast_threshold": lambda: binbow.FeatureExtractor("brief", fast_threshold=value),
        "trees": lambda: binbow.LoopDetector.online("orb", trees=value),
        "stride": lambda: binbow.detect_loops([], stride=value),
    }
    if value != 2**63:  # 64-bit arguments hold 2**63
        calls.update({
            "max_results": lambda: database.query(image, value),
            "max_entry_id": lambda: database.query(image, 10, value),
            "fast_candidates": lambda: database.query(image, 10, fast=True,
                                                      fast_candidates=value),
            "fast_min_postings": lambda: database.query(image, 10, fast=True,
                                                        fast_min_postings=value),
            "seed": lambda: binbow.Vocabulary.build([image, image], seed=value),
            "max_image_pixels": lambda: binbow.FeatureExtractor("orb", max_image_pixels=value),
            "query": lambda: binbow.GroundTruth(5, [(3, 1)]).has_loop(value),
            "frames": lambda: binbow.GroundTruth(value, []),
        })
    for name, call in calls.items():
        with pytest.raises(ValueError, match=rf"^{name} must be in \[") as error:
            call()
        assert "Unable to cast" not in str(error.value), name
    # Entry ids: an id no entry can have is an entry that does not exist.
    for method, call in {
        "label": lambda: database.label(value),
        "set_label": lambda: database.set_label(value, "x"),
        "remove": lambda: database.remove(value),
        "feature_vector": lambda: database.feature_vector(value),
    }.items():
        with pytest.raises(ValueError, match=rf"Database::{method}: entry .* does not exist"):
            call()
    assert value not in database
    assert len(database) == len(images)


def test_64_bit_arguments_take_every_64_bit_int(database, images):
    everything = database.query(images[0], len(images))
    assert database.query(images[0], 2**63) == everything
    assert database.query(images[0], 2**64 - 1, 2**64 - 1) == everything
    assert database.query(images[0], 3, fast=True, fast_min_postings=2**63)


def test_integer_arguments_take_numpy_integers_but_not_bools_or_floats(database, images):
    assert database.query(images[0], np.int64(3)) == database.query(images[0], 3)
    assert database.label(np.uint32(1)) == "image 1"
    with pytest.raises(TypeError, match="max_results must be an int, got bool"):
        database.query(images[0], True)
    with pytest.raises(TypeError, match="entry must be an int, got float"):
        database.label(1.0)
    with pytest.raises(TypeError, match="seed must be an int, got float"):
        binbow.Vocabulary.build(images[:2], seed=1.0)
