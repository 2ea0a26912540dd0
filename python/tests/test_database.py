"""Database: queries against brute force, labels, files, memory usage."""
import os
import subprocess
import sys

import numpy as np
import pytest

import binbow
from conftest import clustered


def test_query_equals_brute_force_and_remove():
    rng = np.random.default_rng(2)
    images = [clustered(rng, 200) for _ in range(30)]
    voc = binbow.Vocabulary.build(images[:10], branching=6, levels=3, seed=1)
    db = binbow.Database(voc)
    for image in images:
        db.add(image)
    assert len(db) == 30
    query = voc.transform(images[7])
    results = db.query(query, max_results=5)
    bows = [voc.transform(image) for image in images]
    brute = sorted((-voc.score(query, b), i) for i, b in enumerate(bows))[:5]
    assert [r[0] for r in results] == [i for _, i in brute]
    for (_, score, _), (negative, _) in zip(results, brute):
        assert score == pytest.approx(-negative, abs=1e-6)
    limited = db.query(query, max_results=30, max_entry_id=4)
    assert sorted(r[0] for r in limited) == [0, 1, 2, 3, 4]
    db.remove(7)
    assert 7 not in [r[0] for r in db.query(query, max_results=30)]
    assert 7 not in db
    with pytest.raises(ValueError):
        db.remove(7)


def test_fast_queries_report_exact_scores():
    rng = np.random.default_rng(4)
    images = [clustered(rng, 200) for _ in range(60)]
    voc = binbow.Vocabulary.build(images[:10], branching=6, levels=3, seed=1)
    db = binbow.Database(voc)
    for image in images:
        db.add(image)
    db.remove(3)
    bows = [voc.transform(image) for image in images]
    for q in (0, 3, 17):
        exact = db.query(bows[q], 10)
        fast = db.query(bows[q], 10, fast=True)
        assert fast and len(fast) <= len(exact)
        for entry, score, _ in fast:
            assert entry != 3
            assert score == voc.score(bows[q], bows[entry])
        assert fast[0] == exact[0]
        assert db.query(bows[q], 10, 5, True) == db.query(bows[q], 10, max_entry_id=5, fast=True)
    with pytest.raises(TypeError):
        db.query(bows[0], 10, fast="yes")
    # Fewer candidates and postings than the defaults: still exact scores only.
    for q in (0, 17):
        few = db.query(bows[q], 10, fast=True, fast_candidates=1, fast_min_postings=0)
        assert few and all(score == voc.score(bows[q], bows[e]) for e, score, _ in few)
    with pytest.raises(ValueError, match="fast_candidates"):
        db.query(bows[0], 10, fast=True, fast_candidates=0)
    assert db.query(bows[17], 10, fast=True, fast_candidates=1, fast_candidate_share=1.0) == \
        db.query(bows[17], 10, fast=True, fast_candidates=len(images))
    with pytest.raises(ValueError, match="fast_candidate_share"):
        db.query(bows[0], 10, fast=True, fast_candidate_share=2.0)
    with pytest.raises(TypeError):
        db.query(bows[0], 10, fast=True, fast_candidate_share="0.1")
    with pytest.raises(ValueError, match="fast=True only"):
        db.query(bows[0], 10, fast_candidates=100)
    with pytest.raises(TypeError):
        db.query(bows[0], 10, fast=True, fast_min_postings="1")


def test_labels(vocabulary, images):
    db = binbow.Database(vocabulary)
    first = db.add(images[0], label="a.png")
    second = db.add(images[1])
    third = db.add_bow(vocabulary.transform(images[2]), label="c.png")
    assert (first, second, third) == (0, 1, 2)
    assert db.label(first) == "a.png"
    assert db.label(second) is None
    assert db.label(third) == "c.png"
    db.set_label(second, "b.png")
    assert db.label(second) == "b.png"
    with pytest.raises(ValueError):
        db.label(99)


def test_an_image_without_features_is_an_empty_entry(vocabulary, images):
    db = binbow.Database(vocabulary)
    db.add(images[0])
    empty = db.add(None, label="blank wall")
    assert empty in db and len(db) == 2
    assert db.label(empty) == "blank wall"
    assert db.feature_vector(empty) == {}
    assert [r[0] for r in db.query(vocabulary.transform(images[0]), 5)] == [0]
    assert db.query(vocabulary.transform(None), 5) == []


def test_save_and_load_with_and_without_vocabulary(tmp_path, database, vocabulary, images):
    query = vocabulary.transform(images[4])
    expected = database.query(query, 5)
    database.save(tmp_path / "full.bbdb")
    database.save(tmp_path / "lean.bbdb", include_vocabulary=False)
    assert binbow.Database.load(tmp_path / "full.bbdb").query(query, 5) == expected
    lean = binbow.Database.load(str(tmp_path / "lean.bbdb"), vocabulary)
    assert lean.query(query, 5) == expected
    assert lean.label(4) == "image 4"
    assert lean.vocabulary.checksum == vocabulary.checksum
    with pytest.raises(OSError, match="does not include its vocabulary"):
        binbow.Database.load(tmp_path / "lean.bbdb")
    other = binbow.Vocabulary.build(images, branching=4, levels=2, seed=9)
    with pytest.raises(OSError, match="different vocabulary"):
        binbow.Database.load(tmp_path / "lean.bbdb", other)
    nested = tmp_path / "new" / "folders" / "db.bbdb"
    database.save(nested)  # the folders are made
    assert binbow.Database.load(nested).query(query, 5) == expected
    with pytest.raises(OSError, match="is a file, not a folder"):
        database.save(tmp_path / "full.bbdb" / "db.bbdb")


def test_incremental_saves_append_to_a_journal(tmp_path, database, vocabulary, images):
    path = tmp_path / "db.bbdb"
    database.save(path)
    base = path.read_bytes()
    added = database.add(images[0], "again")
    database.remove(1)
    database.save_incremental(path)
    assert path.read_bytes() == base  # only the journal was written
    journal = tmp_path / "db.bbdb.journal"
    assert 0 < journal.stat().st_size < len(base)
    query = vocabulary.transform(images[0])
    loaded = binbow.Database.load(path)
    assert loaded.query(query, 10) == database.query(query, 10)
    assert loaded.label(added) == "again" and 1 not in loaded
    database.save(path)  # a full save folds the journal into the file
    assert not journal.exists()
    assert binbow.Database.load(path).query(query, 10) == database.query(query, 10)


def test_one_writer_at_a_time(tmp_path, database, images):
    path = tmp_path / "db.bbdb"
    database.save(path)
    first, second = binbow.Database.load(path), binbow.Database.load(path)
    first.add(images[0])
    with binbow.DatabaseLock(path):
        first.save_incremental(path)  # the holder's own save
    second.add(images[1])
    with pytest.raises(binbow.WriteConflict, match="another writer saved the database"):
        second.save_incremental(path)
    assert isinstance(binbow.WriteConflict("x"), OSError)
    held = binbow.DatabaseLock(path)
    try:
        child = subprocess.run(
            [sys.executable, "-c",
             "import binbow, sys\n"
             "try:\n"
             "    binbow.DatabaseLock(sys.argv[1], wait=0.1)\n"
             "except binbow.WriteConflict as e:\n"
             "    print(e)\n", str(path)],
            capture_output=True, text=True, check=True)
        assert f"process {os.getpid()} holds" in child.stdout
    finally:
        held.release()
    assert len(binbow.Database.load(path)) == len(first)


def test_append_journal_appends_or_writes_nothing(tmp_path, database, images):
    path = tmp_path / "db.bbdb"
    journal = tmp_path / "db.bbdb.journal"
    assert not database.append_journal(path)  # never saved there: a full save is needed
    assert not path.exists()
    database.save(path)
    base = path.read_bytes()
    assert database.append_journal(path) and not journal.exists()  # nothing changed
    database.add(images[0], "again")
    assert database.append_journal(path)
    appended = journal.read_bytes()
    assert path.read_bytes() == base and appended
    # Past a quarter of the file (at least 1 MiB), the journal takes nothing.
    database.add(images[1], "x" * (1 << 20))
    assert not database.append_journal(path)
    assert path.read_bytes() == base and journal.read_bytes() == appended
    assert not database.append_journal(tmp_path / "other.bbdb")
    database.save_incremental(path)  # the full save it asked for
    assert not journal.exists() and binbow.Database.load(path).next_entry_id == len(images) + 2


def damaged_postings(path):
    """Flips a byte in the middle of the postings, the section checked after load returns."""
    data = bytearray(path.read_bytes())
    entry = 64 + 24 * 5  # the section table's row of section 5, the postings
    offset = int.from_bytes(data[entry + 8:entry + 16], "little")
    length = int.from_bytes(data[entry + 16:entry + 24], "little")
    assert length > 100, "the postings section is too small to damage"
    data[offset + length // 2] ^= 0x10
    path.write_bytes(bytes(data))


def test_load_verifies_in_the_background_or_before_returning(tmp_path, database, vocabulary,
                                                            images):
    path = tmp_path / "db.bbdb"
    database.save(path)
    query = vocabulary.transform(images[2])
    expected = database.query(query, 5)
    for verification in ("background", "before-return"):
        loaded = binbow.Database.load(path, verification=verification)
        loaded.wait_until_verified()
        assert loaded.query(query, 5) == expected
    binbow.Database(vocabulary).wait_until_verified()  # nothing to wait for
    damaged_postings(path)
    with pytest.raises(OSError, match=r"db\.bbdb.*'postings'"):
        binbow.Database.load(path, vocabulary, verification="before-return")
    loaded = binbow.Database.load(path, verification="background")  # answers meanwhile
    with pytest.raises(OSError, match=r"db\.bbdb.*'postings'"):
        loaded.wait_until_verified()
    with pytest.raises(OSError, match="'postings'"):
        loaded.query(query, 5)
    with pytest.raises(ValueError, match="unknown verification 'eager'"):
        binbow.Database.load(path, verification="eager")
    with pytest.raises(TypeError):
        binbow.Database.load(path, verification=True)


def test_memory_usage_grows_with_entries(vocabulary, images):
    db = binbow.Database(vocabulary)
    before = db.memory_usage
    for image in images:
        db.add(image)
    assert isinstance(before, int)
    assert db.memory_usage > before


def test_options_and_feature_vectors(vocabulary, images):
    db = binbow.Database(vocabulary, direct_index=True, levels_up=1)
    assert db.direct_index and db.levels_up == 1
    entry = db.add(images[5])
    _, expected = vocabulary.transform_with_features(images[5], levels_up=1)
    got = db.feature_vector(entry)
    assert got.keys() == expected.keys()
    assert all(np.array_equal(got[k], expected[k]) for k in got)
    plain = binbow.Database(vocabulary, direct_index=False)
    plain.add(images[5])
    with pytest.raises(ValueError):
        plain.feature_vector(0)
    db.clear()
    assert len(db) == 0 and db.next_entry_id == 0
    assert "0 entries" in repr(db)
