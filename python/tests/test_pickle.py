"""pickle and copy of Vocabulary, BowVector, Database and loop results."""
import copy
import pickle

import numpy as np
import pytest

import binbow
from conftest import SOURCE_DIR


def test_vocabulary_pickles_as_its_bbw_bytes(tmp_path, vocabulary, images):
    data = pickle.dumps(vocabulary)
    vocabulary.save(tmp_path / "v.bbw")
    assert (tmp_path / "v.bbw").read_bytes() in data
    restored = pickle.loads(data)
    assert isinstance(restored, binbow.Vocabulary)
    assert restored.checksum == vocabulary.checksum
    assert restored.descriptor == vocabulary.descriptor
    assert restored.transform(images[0]) == vocabulary.transform(images[0])


def test_default_vocabulary_round_trips():
    orb = binbow.Vocabulary.default("orb")
    restored = pickle.loads(pickle.dumps(orb, protocol=pickle.HIGHEST_PROTOCOL))
    assert (restored.checksum, restored.descriptor) == (orb.checksum, "orb")


def test_a_damaged_pickled_vocabulary_is_an_error(vocabulary):
    state = bytearray(vocabulary.__getstate__())
    state[len(state) // 2] ^= 0xFF
    with pytest.raises(OSError, match="pickled binbow.Vocabulary"):
        binbow.Vocabulary.__new__(binbow.Vocabulary).__setstate__(bytes(state))


@pytest.mark.parametrize("clone", [copy.copy, copy.deepcopy])
def test_vocabulary_copies(vocabulary, images, clone):
    copied = clone(vocabulary)
    assert copied.checksum == vocabulary.checksum
    assert copied.transform(images[1]) == vocabulary.transform(images[1])


@pytest.mark.parametrize(
    "clone", [copy.copy, copy.deepcopy, lambda b: pickle.loads(pickle.dumps(b))]
)
def test_bow_vector_round_trips(vocabulary, images, clone):
    bow = vocabulary.transform(images[2])
    again = clone(bow)
    assert again == bow and again is not bow
    assert np.array_equal(again.words, bow.words)
    empty = vocabulary.transform(None)
    assert clone(empty) == empty


def test_database_pickles_with_its_vocabulary_entries_and_labels(database, vocabulary, images):
    database.remove(3)
    restored = pickle.loads(pickle.dumps(database))
    assert len(restored) == len(database) == len(images) - 1
    assert 3 not in restored
    assert restored.label(5) == "image 5"
    assert restored.next_entry_id == database.next_entry_id
    assert restored.vocabulary.checksum == vocabulary.checksum
    query = vocabulary.transform(images[6])
    assert restored.query(query, 5) == database.query(query, 5)
    assert restored.feature_vector(6).keys() == database.feature_vector(6).keys()


@pytest.mark.parametrize("clone", [copy.copy, copy.deepcopy])
def test_database_copies_are_independent(database, vocabulary, images, clone):
    copied = clone(database)
    assert len(copied) == len(database)
    copied.add(images[0], label="only in the copy")
    copied.remove(0)
    assert len(copied) == len(database) and 0 in database and 0 not in copied
    assert copied.label(len(images)) == "only in the copy"
    assert copied.levels_up == database.levels_up
    query = vocabulary.transform(images[1])
    assert copied.query(query, 3) == database.query(query, 3)


LOOP_RESULT_FIELDS = (
    "file", "match_file", "status", "detection", "query", "match", "score",
    "normalisation_score", "normalised_score", "island", "island_score", "consistent_queries",
    "correspondences", "exhaustive_fallback_used", "fit_evidence", "accepted_by", "times",
)


def test_loop_results_round_trip():
    folder = SOURCE_DIR / "data" / "samples" / "rtabmap" / "samples"
    results = binbow.detect_loops(folder, stride=2)
    for clone in (pickle.loads(pickle.dumps(results)), copy.deepcopy(results)):
        assert isinstance(clone, binbow.LoopResults) and len(clone) == len(results)
        assert clone.params == results.params and clone.inputs == results.inputs
        assert clone.vocabulary.checksum == results.vocabulary.checksum
        for a, b in zip(results, clone):
            for name in LOOP_RESULT_FIELDS:
                assert getattr(a, name) == getattr(b, name), name
            np.testing.assert_array_equal(a.inliers, b.inliers)
            np.testing.assert_array_equal(a.inlier_points, b.inlier_points)
    assert any(r.detection for r in results), "the round trip covered a detection"
    with pytest.raises(ValueError, match="LoopResult"):
        binbow.LoopResult.__new__(binbow.LoopResult).__setstate__(("x",))
