"""Vocabulary: building, transforms against brute force, files, the bundled defaults."""
import os
import struct

import numpy as np
import pytest

import binbow
from conftest import SOURCE_DIR, clustered


def test_hamming_matches_numpy(images):
    a, b = images[0][0], images[0][1]
    assert binbow.hamming(a, b) == int(np.unpackbits(a ^ b).sum())


def test_build_is_deterministic_and_describes_itself(images, vocabulary):
    again = binbow.Vocabulary.build(images, branching=5, levels=3, seed=3, threads=1)
    assert again.checksum == vocabulary.checksum
    assert vocabulary.word_count == again.word_count
    assert vocabulary.branching == 5
    assert vocabulary.levels == 3
    assert vocabulary.code_size == 32
    assert vocabulary.weighting == "tf-idf"
    assert vocabulary.scoring == "l1"
    assert "k=5 L=3" in repr(vocabulary)


def test_transform_is_sorted_normalised_and_consistent_with_quantize(images, vocabulary):
    bow = vocabulary.transform(images[0])
    words = bow.words
    assert np.all(np.diff(words.astype(np.int64)) > 0)
    assert float(np.abs(bow.values).sum()) == pytest.approx(1.0, abs=1e-5)
    assert set(words.tolist()) <= set(vocabulary.quantize(images[0]).tolist())
    assert vocabulary.score(bow, bow) == pytest.approx(1.0, abs=1e-5)


def test_feature_vector_covers_every_feature_once(vocabulary, images):
    _, fv = vocabulary.transform_with_features(images[1], levels_up=1)
    covered = sorted(i for indices in fv.values() for i in indices.tolist())
    assert covered == list(range(len(images[1])))


def test_save_load_round_trip_with_str_and_pathlike(tmp_path, vocabulary, images):
    path = tmp_path / "v.bbw"
    vocabulary.save(path)
    assert binbow.Vocabulary.load(path).transform(images[2]) == vocabulary.transform(images[2])
    assert binbow.Vocabulary.load(str(path)).checksum == vocabulary.checksum


def test_vins_binary_round_trip_and_explicit_formats(tmp_path, vocabulary, images):
    path = tmp_path / "brief_k10L6.bin"
    vocabulary.save(path, format="vins")
    data = path.read_bytes()
    k, levels, _, _, nodes, words = struct.unpack_from("<6i", data)
    assert (k, levels, words, nodes + 1) == (5, 3, vocabulary.word_count, vocabulary.node_count)
    assert len(data) == 24 + 48 * nodes + 8 * words
    again = binbow.Vocabulary.load(path)  # by content: a plain .bin would be ORB-SLAM's
    assert again.checksum == vocabulary.checksum
    assert again.transform(images[2]) == vocabulary.transform(images[2])
    assert binbow.Vocabulary.load(str(path), format="vins").checksum == vocabulary.checksum
    vocabulary.save(tmp_path / "v.vins.bin")
    assert (tmp_path / "v.vins.bin").read_bytes() == data
    with pytest.raises(OSError, match="brief_k10L6.bin"):
        binbow.Vocabulary.load(path, format="dbow3")
    with pytest.raises(ValueError, match="unknown vocabulary format 'morse'"):
        vocabulary.save(tmp_path / "x.bin", format="morse")
    rng = np.random.default_rng(2)
    wide = binbow.Vocabulary.build([clustered(rng, 100, code_size=64) for _ in range(3)],
                                   branching=3, levels=2, weighting="tf")
    with pytest.raises(ValueError, match="256-bit descriptors only"):
        wide.save(tmp_path / "wide.vins.bin")
    assert not (tmp_path / "wide.vins.bin").exists()


def test_records_the_descriptor_it_was_trained_on(tmp_path, images, vocabulary):
    assert vocabulary.descriptor == ""
    orb = binbow.Vocabulary.build(images, branching=5, levels=2, descriptor="orb")
    orb.save(tmp_path / "orb.bbw")
    assert binbow.Vocabulary.load(tmp_path / "orb.bbw").descriptor == "orb"
    with pytest.raises(ValueError):
        binbow.Vocabulary.build(images, branching=5, levels=2, descriptor="ORB!")


def test_files_that_do_not_record_the_descriptor_take_it_or_say_what_is_assumed(
        tmp_path, images, capfd):
    brief = binbow.Vocabulary.build(images, branching=5, levels=2, descriptor="brief")
    brief.save(tmp_path / "v.yml.gz")
    brief.save(tmp_path / "v.vins.bin")
    capfd.readouterr()
    assumed = binbow.Vocabulary.load(tmp_path / "v.yml.gz")
    assert assumed.descriptor == "orb"
    assert capfd.readouterr().err == (
        f"binbow: warning: {tmp_path / 'v.yml.gz'}: dbow2 files do not store the descriptor "
        "kind; assuming orb (give --descriptor brief, or descriptor=\"brief\" in Python, if it "
        "is BRIEF)\n")
    told = binbow.Vocabulary.load(tmp_path / "v.yml.gz", descriptor="brief")
    assert told.descriptor == "brief" and told.checksum == brief.checksum
    assert binbow.Vocabulary.load(tmp_path / "v.vins.bin").descriptor == "brief"
    assert capfd.readouterr().err == ""
    with pytest.raises(ValueError, match="descriptor name"):
        binbow.Vocabulary.load(tmp_path / "v.yml.gz", descriptor="BRIEF!")


def test_stop_words_get_weight_zero(images):
    # With a fraction of 0.5 every word present in more than half of the
    # images is a stop word: transforms become sparser.
    plain = binbow.Vocabulary.build(images, branching=5, levels=3, seed=1)
    stopped = binbow.Vocabulary.build(images, branching=5, levels=3, seed=1,
                                      stop_word_fraction=0.5)
    assert stopped.checksum != plain.checksum
    assert len(stopped.transform(images[0])) < len(plain.transform(images[0]))
    with pytest.raises(ValueError, match="stop_word_fraction"):
        binbow.Vocabulary.build(images, stop_word_fraction=1.5)


def test_max_iterations_changes_the_clustering(images):
    one = binbow.Vocabulary.build(images, branching=8, levels=2, seed=2, max_iterations=1)
    many = binbow.Vocabulary.build(images, branching=8, levels=2, seed=2, max_iterations=30)
    assert one.checksum != many.checksum


def test_progress_is_reported_until_every_descriptor_is_clustered(images):
    reports = []
    binbow.Vocabulary.build(images, branching=5, levels=3, progress=reports.append)
    assert reports, "progress was never called"
    assert all(isinstance(r, binbow.BuildProgress) for r in reports)
    total = sum(len(image) for image in images)
    assert reports[-1].total_descriptors == total
    assert reports[-1].clustered_descriptors == total
    assert reports[-1].nodes > 1
    assert "descriptors" in repr(reports[-1])


def test_an_exception_in_progress_stops_the_build(images):
    def interrupt(_):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        binbow.Vocabulary.build(images, branching=5, levels=3, threads=2, progress=interrupt)
    with pytest.raises(TypeError, match="progress must be callable"):
        binbow.Vocabulary.build(images, progress=3)


def test_images_without_features_count_as_images(images):
    with_empty = binbow.Vocabulary.build(images + [None, np.empty((0, 32), np.uint8)],
                                         branching=5, levels=3, seed=3)
    plain = binbow.Vocabulary.build(images, branching=5, levels=3, seed=3)
    # Same tree, different IDF weights (N counts the empty images).
    assert with_empty.node_count == plain.node_count
    assert with_empty.checksum != plain.checksum


@pytest.mark.parametrize("descriptor, code_size", [("orb", 32), ("brief", 32)])
def test_default_vocabularies_are_the_bundled_files(descriptor, code_size):
    vocabulary = binbow.Vocabulary.default(descriptor)
    bundled = binbow.Vocabulary.load(SOURCE_DIR / "data" / "vocab" / f"{descriptor}_default.bbw")
    assert vocabulary.checksum == bundled.checksum
    assert vocabulary.descriptor == descriptor
    assert vocabulary.code_size == code_size


def test_default_vocabulary_errors(monkeypatch, tmp_path):
    with pytest.raises(ValueError, match="'sift'"):
        binbow.Vocabulary.default("sift")
    # BINBOW_DATA_DIR comes first.
    (tmp_path / "vocab").mkdir()
    rng = np.random.default_rng(5)
    own = binbow.Vocabulary.build([clustered(rng, 100)], branching=3, levels=2, weighting="tf")
    own.save(tmp_path / "vocab" / "brief_default.bbw")
    monkeypatch.setenv("BINBOW_DATA_DIR", str(tmp_path))
    assert binbow.data_directories()[0] == str(tmp_path)
    assert binbow.Vocabulary.default("brief").checksum == own.checksum
    assert binbow.Vocabulary.default("orb").descriptor == "orb"  # from the bundled data


def test_default_vocabulary_missing_names_the_places_searched(monkeypatch, tmp_path):
    import binbow._data_location as location

    monkeypatch.setattr(location, "DATA_DIRECTORY", os.fspath(tmp_path / "nowhere"))
    with pytest.raises(FileNotFoundError, match="nowhere"):
        binbow.Vocabulary.default("orb")


def test_errors_are_python_exceptions(vocabulary):
    with pytest.raises(OSError, match="nonexistent"):
        binbow.Vocabulary.load("/nonexistent/v.bbw")
    with pytest.raises(ValueError):
        binbow.Vocabulary.build([], branching=5)
    with pytest.raises(ValueError, match="weighting"):
        binbow.Vocabulary.build([np.zeros((3, 32), np.uint8)], weighting="tfidf!")
    assert issubclass(binbow.Error, RuntimeError)
    assert binbow.Error.__module__ == "binbow"
