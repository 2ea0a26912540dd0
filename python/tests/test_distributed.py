"""binbow.distributed.ShardedDatabase on a local Dask cluster of worker processes."""
import contextlib
import json
import os
import pickle
import signal
import warnings

import numpy as np
import pytest

import binbow
from conftest import clustered, require_module, sample_frames


def saved_files(folder):
    """The files of a save; each shard's writer lock (.lock, a pid) stays beside it too."""
    return [p for p in folder.iterdir() if not p.name.endswith(".lock")]


@pytest.fixture(scope="module")
def client():
    distributed = require_module("distributed", "python3-distributed")
    cluster = distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                       dashboard_address=None)
    with distributed.Client(cluster) as dask_client:
        yield dask_client
    cluster.close()


@contextlib.contextmanager
def own_cluster():
    """A client of two worker processes of the test's own, for a test that kills one: the
    module's shared cluster stays whole."""
    distributed = require_module("distributed", "python3-distributed")
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as dask_client:
        yield dask_client


def kill_worker(dask_client, worker):
    os.kill(dask_client.run(os.getpid, workers=[worker])[worker], signal.SIGKILL)


def sharded_module():
    return require_module("binbow.distributed", "python3-distributed")


def random_images(seed, count):
    rng = np.random.default_rng(seed)
    return [clustered(rng, 150) for _ in range(count)]


def both(client, vocabulary, images, shards, labels=None):
    """A single Database and a ShardedDatabase holding the same entries."""
    single = binbow.Database(vocabulary)
    for index, image in enumerate(images):
        single.add(image, None if labels is None else labels[index])
    sharded = sharded_module().ShardedDatabase(client, vocabulary, shards=shards)
    assert sharded.add_many(images, labels) == list(range(len(images)))
    return single, sharded


def assert_same_answers(single, sharded, queries, max_entry_ids=(None,)):
    for query in queries:
        for max_results in (1, 3, 10, 100):
            for max_entry_id in max_entry_ids:
                expected = single.query(query, max_results, max_entry_id)
                assert expected, "the query should match something"
                assert sharded.query(query, max_results, max_entry_id) == expected


@pytest.mark.parametrize("shards", [1, 3])
def test_queries_equal_one_database_with_ties(client, vocabulary, shards):
    images = random_images(5, 10)
    # Duplicates score equally: the tie order (increasing id) must cross shards.
    images = images + [images[2], images[7], images[2], images[2]]
    single, sharded = both(client, vocabulary, images, shards)
    bows = [vocabulary.transform(image) for image in images]
    tied = single.query(bows[2], 4)
    assert [entry for entry, _, _ in tied] == [2, 10, 12, 13]
    assert_same_answers(single, sharded, bows[:4] + [bows[7]], (None, 0, 5, 12, 100))
    assert sharded.query(images[2], 4) == tied  # descriptors are transformed on the client
    for bow in bows[:4]:  # fast mode on every shard: exact scores, merged as usual
        exact = {entry: (score, shared) for entry, score, shared in single.query(bow, 100)}
        fast = sharded.query(bow, 5, fast=True)
        assert fast and fast[0] == single.query(bow, 1)[0]
        assert all(exact[entry] == (score, shared) for entry, score, shared in fast)
        if shards == 1:  # one shard holds what the one Database holds
            assert fast == single.query(bow, 5, fast=True)
    assert len(sharded) == len(images) and sharded.next_entry_id == len(images)


def test_single_adds_return_dense_ids_and_bow_vectors_work(client, vocabulary):
    images = random_images(6, 7)
    sharded = sharded_module().ShardedDatabase(client, vocabulary, shards=3)
    ids = [sharded.add(vocabulary.transform(image) if i % 2 else image, label=f"n{i}")
           for i, image in enumerate(images)]
    assert ids == list(range(7))
    assert [sharded.label(i) for i in ids] == [f"n{i}" for i in ids]
    assert sharded.add(None) == 7  # an image without features still gets an id


def test_real_descriptors(client):
    vocabulary = binbow.Vocabulary.default("orb")
    extractor = binbow.FeatureExtractor("orb", max_features=500)
    images = [extractor.extract(str(frame))[1] for frame in sample_frames()[:24]]
    single, sharded = both(client, vocabulary, images, 3)
    queries = [vocabulary.transform(images[i]) for i in (0, 11, 23)]
    assert_same_answers(single, sharded, queries, (None, 10))
    for query in queries:  # fast mode: the exact top 1, every score exact
        exact = {entry: (score, shared) for entry, score, shared in single.query(query, 100)}
        fast = sharded.query(query, 10, fast=True)
        assert fast[0] == single.query(query, 1)[0]
        assert all(exact[entry] == (score, shared) for entry, score, shared in fast)


def test_fast_query_options_reach_every_shard(client, tmp_path):
    """Each shard answers as a Database loaded from its file with the same options."""
    vocabulary = binbow.Vocabulary.default("orb")
    extractor = binbow.FeatureExtractor("orb", max_features=500)
    images = [extractor.extract(str(frame))[1] for frame in sample_frames()]
    module = sharded_module()
    # Loaded from files, as a large database is: its queries then read only
    # some words when the options let them.
    sharded = module.ShardedDatabase(client, vocabulary, shards=2)
    sharded.add_many(images)
    sharded.save(tmp_path)
    loaded = module.ShardedDatabase.load(client, tmp_path, vocabulary)
    files = json.loads((tmp_path / "manifest.json").read_text(encoding="utf-8"))["files"]
    shards = [binbow.Database.load(str(tmp_path / name), vocabulary) for name in files]

    def merged(bow, **options):  # the shards' answers, merged as one Database's
        found = [(shard + local * 2, score, shared) for shard, db in enumerate(shards)
                 for local, score, shared in db.query(bow, 5, fast=True, **options)]
        return sorted(found, key=lambda result: (-result[1], result[0]))[:5]

    few = {"fast_candidates": 1, "fast_min_postings": 0}
    every = {"fast_candidates": 1, "fast_candidate_share": 1.0, "fast_min_postings": 0}
    changed = 0
    for image in images:
        bow = vocabulary.transform(image)
        exact = loaded.query(bow, 5)
        assert loaded.query(bow, 5, fast=True, **every) == exact
        tuned = loaded.query(bow, 5, fast=True, **few)
        assert tuned == merged(bow, **few)
        changed += tuned != exact
    assert changed > 0, "one candidate from few postings should change some top 5"


def test_remove_and_labels(client, vocabulary):
    images = random_images(7, 9)
    labels = [f"place {i}" if i % 3 else None for i in range(9)]
    single, sharded = both(client, vocabulary, images, 3, labels)
    for entry in (1, 5, 6):
        single.remove(entry)
        sharded.remove(entry)
    assert len(sharded) == 6 and 5 not in sharded and 4 in sharded and 99 not in sharded
    assert [sharded.label(i) for i in (0, 2, 4)] == [labels[i] for i in (0, 2, 4)]
    sharded.set_label(0, "origin")
    assert sharded.label(0) == "origin"
    assert_same_answers(single, sharded, [vocabulary.transform(images[i]) for i in (1, 4)])
    with pytest.raises(ValueError, match=r"Database::remove: entry 5 was removed"):
        sharded.remove(5)  # already removed: the shard's Database says so
    with pytest.raises(ValueError, match="entry 9 does not exist"):
        sharded.label(9)
    assert sharded.add(images[0]) == 9  # removed ids are never reused


def test_save_and_load_round_trip(client, vocabulary, tmp_path):
    images = random_images(8, 11)
    single, sharded = both(client, vocabulary, images, 3, [f"l{i}" for i in range(11)])
    sharded.remove(10)  # the last id stays used after loading
    single.remove(10)
    sharded.save(tmp_path)
    manifest = json.loads((tmp_path / "manifest.json").read_text(encoding="utf-8"))
    assert manifest["shards"] == 3 and manifest["next_entry_id"] == 11
    assert manifest["vocabulary_checksum"] == vocabulary.checksum
    assert sorted(p.name for p in saved_files(tmp_path)) == [
        "manifest.json", "shard-0.gen1.bbdb", "shard-1.gen1.bbdb", "shard-2.gen1.bbdb"]
    loaded = sharded_module().ShardedDatabase.load(client, tmp_path, vocabulary)
    assert loaded.shards == 3 and len(loaded) == 10 and loaded.label(4) == "l4"
    assert_same_answers(single, loaded, [vocabulary.transform(images[i]) for i in (0, 3, 9)])
    assert loaded.add(images[1]) == 11
    # The next save is a new generation; the previous one is removed once committed.
    loaded.save(tmp_path)
    assert sorted(p.name for p in saved_files(tmp_path)) == [
        "manifest.json", "shard-0.gen2.bbdb", "shard-1.gen2.bbdb", "shard-2.gen2.bbdb"]
    assert sharded_module().ShardedDatabase.load(client, tmp_path, vocabulary).label(4) == "l4"


def test_incremental_saves_append_to_the_shards_journals(client, vocabulary, tmp_path):
    images = random_images(21, 12)
    single, sharded = both(client, vocabulary, images[:6], 2, [f"l{i}" for i in range(6)])
    module = sharded_module()
    sharded.save_incremental(tmp_path)  # never saved: a full save
    assert not list(tmp_path.glob("*.journal"))
    saved = {path.name: path.read_bytes() for path in tmp_path.glob("*.bbdb")}
    for image in images[6:8]:
        single.add(image)
    sharded.add_many(images[6:8])
    sharded.save_incremental(tmp_path)  # right after a full save, the shards append
    manifest = json.loads((tmp_path / "manifest.json").read_text(encoding="utf-8"))
    journals = [tmp_path / (name + ".journal") for name in manifest["files"]]
    assert all(path.stat().st_size > 0 for path in journals)
    assert {path.name: path.read_bytes() for path in tmp_path.glob("*.bbdb")} == saved
    for image in images[8:10]:
        single.add(image)
    sharded.add_many(images[8:10])
    single.remove(3)
    sharded.remove(3)
    sharded.save_incremental(tmp_path)
    manifest = json.loads((tmp_path / "manifest.json").read_text(encoding="utf-8"))
    assert manifest["journal_bytes"] == [path.stat().st_size for path in journals]
    assert all(size > 0 for size in manifest["journal_bytes"])
    assert {path.name: path.read_bytes() for path in tmp_path.glob("*.bbdb")} == saved
    queries = [vocabulary.transform(images[i]) for i in (0, 7, 9)]
    loaded = module.ShardedDatabase.load(client, tmp_path, vocabulary)
    assert_same_answers(single, loaded, queries)
    # A save that stopped before its manifest: load cuts the journals back.
    committed = (tmp_path / "manifest.json").read_bytes()
    loaded.add_many(images[10:12])
    loaded.save_incremental(tmp_path)
    assert journals[0].stat().st_size > manifest["journal_bytes"][0]
    (tmp_path / "manifest.json").write_bytes(committed)
    again = module.ShardedDatabase.load(client, tmp_path, vocabulary)
    assert [path.stat().st_size for path in journals] == manifest["journal_bytes"]
    assert again.next_entry_id == 10 and len(again) == 9
    assert_same_answers(single, again, queries)
    # A full save removes the journals.
    again.save(tmp_path)
    assert not list(tmp_path.glob("*.journal"))


def test_load_refuses_another_vocabulary_and_broken_manifests(client, vocabulary, tmp_path):
    sharded = sharded_module().ShardedDatabase(client, vocabulary, shards=2)
    sharded.add_many(random_images(9, 3))
    sharded.save(tmp_path)
    other = binbow.Vocabulary.build(random_images(10, 4), branching=4, levels=2, seed=1)
    with pytest.raises(binbow.Error, match="checksum"):
        sharded_module().ShardedDatabase.load(client, tmp_path, other)
    manifest = json.loads((tmp_path / "manifest.json").read_text(encoding="utf-8"))
    manifest["next_entry_id"] = 5
    (tmp_path / "manifest.json").write_text(json.dumps(manifest), encoding="utf-8")
    with pytest.raises(binbow.Error, match=r"shard-0.gen1.bbdb holds 2 ids"):
        sharded_module().ShardedDatabase.load(client, tmp_path, vocabulary)
    with pytest.raises(binbow.Error, match="cannot read"):
        sharded_module().ShardedDatabase.load(client, tmp_path / "missing", vocabulary)


def test_bad_inputs_are_refused_before_any_shard_adds(client, vocabulary):
    module = sharded_module()
    sharded = module.ShardedDatabase(client, vocabulary, shards=2)
    good = random_images(11, 1)[0]
    with pytest.raises(ValueError, match=r"images\[1\] have 16 bytes"):
        sharded.add_many([good, good[:, :16]])
    with pytest.raises(ValueError, match="outside the vocabulary"):
        sharded.add(binbow.BowVector(np.array([vocabulary.word_count]), np.array([1.0])))
    assert len(sharded) == 0 and sharded.add(good) == 0
    with pytest.raises(ValueError, match="max_results"):
        sharded.query(good, -1)
    with pytest.raises(TypeError, match="distributed.Client"):
        module.ShardedDatabase(object(), vocabulary)
    with pytest.raises(ValueError, match="shards"):
        module.ShardedDatabase(client, vocabulary, shards=0)


def test_the_workers_hold_the_shards(client, vocabulary):
    sharded = sharded_module().ShardedDatabase(client, vocabulary, shards=4)
    assert len(set(sharded.workers)) == 2  # spread over both workers


def test_the_vocabulary_is_sent_to_each_worker_not_in_every_shard_s_task(client, tmp_path):
    """Dask warns when a task carries more than 1 MB: a large vocabulary is
    scattered once to the workers, which their shards share."""
    rng = np.random.default_rng(17)
    large = binbow.Vocabulary.build(
        [rng.integers(0, 256, size=(1000, 32), dtype=np.uint8) for _ in range(40)],
        branching=16, levels=4, seed=1, max_iterations=2)
    assert len(pickle.dumps(large)) > 1_000_000
    module = sharded_module()
    worker_module = require_module("distributed.worker", "python3-distributed")
    images = random_images(18, 6)
    with warnings.catch_warnings():
        warnings.filterwarnings("error", message="Large object")
        # Dask warns once per process: a large task of another test must not hide this one.
        worker_module._warn_dumps_warned[0] = False
        sharded = module.ShardedDatabase(client, large, shards=4)
        sharded.add_many(images)
        sharded.save(tmp_path)
        worker_module._warn_dumps_warned[0] = False
        loaded = module.ShardedDatabase.load(client, tmp_path, large)
    single = binbow.Database(large)
    for image in images:
        single.add(image)
    assert_same_answers(loaded, sharded, [large.transform(images[i]) for i in (0, 5)])
    assert_same_answers(single, loaded, [large.transform(images[i]) for i in (0, 5)])


def test_every_public_method_has_a_docstring():
    cls = sharded_module().ShardedDatabase
    public = [name for name in vars(cls) if not name.startswith("_")]
    assert public and all(getattr(cls, name).__doc__ for name in public)


def raised(call):
    """(exception class, message) of a call that must fail."""
    with pytest.raises(Exception) as error:
        call()
    return type(error.value), str(error.value)


def add_bow(db, bow):
    """Database.add_bow, or ShardedDatabase.add (which takes BowVectors too)."""
    return db.add_bow(bow) if isinstance(db, binbow.Database) else db.add(bow)


def test_the_same_mistakes_give_database_s_errors(client, vocabulary):
    images = random_images(12, 4)
    single, sharded = both(client, vocabulary, images, 3)
    single.remove(2)
    sharded.remove(2)
    good = images[0]
    outside = binbow.BowVector(np.array([vocabulary.word_count]), np.array([1.0]))
    infinite = binbow.BowVector(np.array([1]), np.array([np.inf]))
    mistakes = {
        "float descriptors": lambda db: db.add(good.astype(np.float32)),
        "int descriptors": lambda db: db.add(good.astype(np.int64)),
        "a list": lambda db: db.add(good.tolist()),
        "1-D": lambda db: db.add(good[0]),
        "short rows": lambda db: db.add(good[:, :16]),
        "word outside": lambda db: add_bow(db, outside),
        "infinite value": lambda db: add_bow(db, infinite),
        "label type": lambda db: db.add(good, 7),
        "query float": lambda db: db.query(good.astype(np.float64)),
        "query list": lambda db: db.query([1, 2]),
        "negative max_results": lambda db: db.query(good, -1),
        "bool max_results": lambda db: db.query(good, True),
        "negative max_entry_id": lambda db: db.query(good, 3, -1),
        "remove removed": lambda db: db.remove(2),
        "remove beyond": lambda db: db.remove(4),
        "label removed": lambda db: db.label(2),
        "label beyond": lambda db: db.label(40),
        "set_label beyond": lambda db: db.set_label(4, "x"),
    }
    for name, mistake in mistakes.items():
        assert raised(lambda: mistake(sharded)) == raised(lambda: mistake(single)), name
    assert len(sharded) == len(single) == 3 and sharded.next_entry_id == 4
    # The fast-mode options are refused before any shard is called.
    fast_mistakes = {
        "fast_candidates without fast": lambda db: db.query(good, fast_candidates=5),
        "fast_min_postings with fast=False": lambda db: db.query(good, 3, None, False,
                                                                 fast_min_postings=0),
        "no candidates": lambda db: db.query(good, fast=True, fast_candidates=0),
        "float candidates": lambda db: db.query(good, fast=True, fast_candidates=2.0),
        "bool candidates": lambda db: db.query(good, fast=True, fast_candidates=True),
        "share above 1": lambda db: db.query(good, fast=True, fast_candidate_share=1.5),
        "negative share": lambda db: db.query(good, fast=True, fast_candidate_share=-0.1),
        "NaN share": lambda db: db.query(good, fast=True, fast_candidate_share=float("nan")),
        "text share": lambda db: db.query(good, fast=True, fast_candidate_share="0.1"),
        "negative min postings": lambda db: db.query(good, fast=True, fast_min_postings=-1),
        "float min postings": lambda db: db.query(good, fast=True, fast_min_postings=1.0),
    }

    def no_shard_call(*arguments, **keywords):
        raise AssertionError("a shard was called")
    sharded._call_all = no_shard_call
    for name, mistake in fast_mistakes.items():
        expected = raised(lambda: mistake(single))
        assert expected[0] in (TypeError, ValueError), name
        assert raised(lambda: mistake(sharded)) == expected, name


def test_a_lost_worker_is_a_binbow_error_and_the_last_save_stays(vocabulary, tmp_path):
    """A worker dies: calls raise binbow.Error, save refuses before writing anything."""
    module = sharded_module()
    images = random_images(13, 6)
    with own_cluster() as dask_client:
        sharded = module.ShardedDatabase(dask_client, vocabulary, shards=2, timeout=20)
        sharded.add_many(images[:4], [f"l{i}" for i in range(4)])
        sharded.save(tmp_path)
        saved = {p.name: p.read_bytes() for p in saved_files(tmp_path)}
        sharded.add_many(images[4:])  # a newer generation, on both shards
        kill_worker(dask_client, sharded.workers[1])
        with pytest.raises(binbow.Error, match="shard 1"):
            sharded.query(images[1])
        for call in (lambda: sharded.save(tmp_path), lambda: sharded.add(images[0]),
                     lambda: sharded.query(images[0]), lambda: sharded.label(0), lambda: len(sharded)):
            with pytest.raises(binbow.Error, match="shard 1 was lost.*load the last save"):
                call()
        assert {p.name: p.read_bytes() for p in saved_files(tmp_path)} == saved
        dask_client.wait_for_workers(2, timeout=60)  # the nanny restarts the dead worker
        loaded = module.ShardedDatabase.load(dask_client, tmp_path, vocabulary, timeout=20)
        assert len(loaded) == 4 and loaded.label(3) == "l3" and loaded.next_entry_id == 4


@pytest.mark.parametrize("first", ["query", "len", "save"])
def test_the_call_that_meets_a_killed_worker_names_the_shard_and_what_to_do(vocabulary, tmp_path,
                                                                           first):
    """Whichever call meets the dead worker first, it raises binbow.Error (never Dask's own
    exception) naming the shard and the way back; every later call says the shard was lost."""
    module = sharded_module()
    images = random_images(16, 4)
    with own_cluster() as dask_client:
        sharded = module.ShardedDatabase(dask_client, vocabulary, shards=2, timeout=20)
        sharded.add_many(images)
        calls = {"query": lambda: sharded.query(images[0]), "len": lambda: len(sharded),
                 "save": lambda: sharded.save(tmp_path / "saved")}
        kill_worker(dask_client, sharded.workers[1])
        with pytest.raises(binbow.Error, match=r"^ShardedDatabase[.: ].*shard 1 .*"
                                               r"ShardedDatabase\.load\)$") as raised:
            calls[first]()
        assert type(raised.value) is binbow.Error
        for name, call in calls.items():
            with pytest.raises(binbow.Error, match="shard 1 was lost.*load the last save"):
                call()
        assert not (tmp_path / "saved" / "manifest.json").exists()


def test_a_shard_lost_during_a_save_leaves_the_previous_save(client, vocabulary, tmp_path):
    """Shard files replace the previous ones only once every shard has written."""
    sharded = sharded_module().ShardedDatabase(client, vocabulary, shards=2)
    sharded.add_many(random_images(14, 4))
    sharded.save(tmp_path)
    saved = {p.name: p.read_bytes() for p in saved_files(tmp_path)}
    sharded.add_many(random_images(15, 2))
    # Shard 1 cannot write its file (a folder holds the name of its next
    # generation): shard 0 has written its own by then, which must not replace
    # the saved one.
    (tmp_path / "shard-1.gen2.bbdb").mkdir()
    with pytest.raises(OSError):
        sharded.save(tmp_path)
    (tmp_path / "shard-1.gen2.bbdb").rmdir()
    assert {p.name: p.read_bytes() for p in saved_files(tmp_path)} == saved
    # The shards' files changed: the next incremental save is a full one.
    sharded.save_incremental(tmp_path)
    assert not list(tmp_path.glob("*.journal"))
    loaded = sharded_module().ShardedDatabase.load(client, tmp_path, vocabulary)
    assert len(loaded) == 6


def test_saves_named_without_generation_still_load_and_append(client, vocabulary, tmp_path):
    """A manifest may name shard-<i>.bbdb: loaded, appended to, then replaced by a full save."""
    images = random_images(16, 6)
    single, sharded = both(client, vocabulary, images[:4], 2)
    sharded.save(tmp_path)
    manifest = json.loads((tmp_path / "manifest.json").read_text(encoding="utf-8"))
    for shard, name in enumerate(manifest["files"]):
        (tmp_path / name).rename(tmp_path / f"shard-{shard}.bbdb")
    manifest["files"] = ["shard-0.bbdb", "shard-1.bbdb"]
    (tmp_path / "manifest.json").write_text(json.dumps(manifest), encoding="utf-8")
    module = sharded_module()
    loaded = module.ShardedDatabase.load(client, tmp_path, vocabulary)
    loaded.add_many(images[4:])
    for image in images[4:]:
        single.add(image)
    loaded.save_incremental(tmp_path)
    assert sorted(p.name for p in tmp_path.glob("*.journal")) == [
        "shard-0.bbdb.journal", "shard-1.bbdb.journal"]
    queries = [vocabulary.transform(images[i]) for i in (0, 5)]
    reloaded = module.ShardedDatabase.load(client, tmp_path, vocabulary)
    assert_same_answers(single, reloaded, queries)
    loaded.save(tmp_path)
    assert sorted(p.name for p in saved_files(tmp_path)) == [
        "manifest.json", "shard-0.gen1.bbdb", "shard-1.gen1.bbdb"]
    reloaded = module.ShardedDatabase.load(client, tmp_path, vocabulary)
    assert_same_answers(single, reloaded, queries)


# Run in a process of its own, killed (SIGKILL) at the Nth call that changes a
# file: a shard's save or append (a shard's own file writes are atomic,
# docs/database-files.md) or the client's renames, removals and truncations.
# The workers are threads of that process, so the kill stops every writer at
# once, as a crash of the machine would. Prints the calls made when not killed.
_KILLED_SAVE = r"""
import os, signal, sys, threading
import numpy as np
import binbow, distributed
import binbow.distributed as sharded

folder, vocabulary_path, kind, kill_at = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
vocabulary = binbow.Vocabulary.load(vocabulary_path)
calls, lock, counting = [0], threading.Lock(), [False]

def step():
    with lock:
        if counting[0]:
            calls[0] += 1
            if calls[0] == kill_at:
                os.kill(os.getpid(), signal.SIGKILL)

def counted(function):
    def call(*arguments, **keywords):
        step()
        return function(*arguments, **keywords)
    return call

for name in ("replace", "rename", "unlink", "remove", "truncate"):
    setattr(os, name, counted(getattr(os, name)))
shard_call = sharded._Shard.call
def call(self, method, *arguments):
    if method in ("save", "save_incremental", "append_journal"):
        step()
    return shard_call(self, method, *arguments)
sharded._Shard.call = call

rng = np.random.default_rng(30)
with distributed.LocalCluster(n_workers=2, processes=False, threads_per_worker=1,
                              dashboard_address=None) as cluster, \
        distributed.Client(cluster) as client:
    db = sharded.ShardedDatabase.load(client, folder, vocabulary)
    if kind == "incremental":
        # Entry 8 goes to shard 0, whose journal it overflows: that shard is
        # written whole; shard 1 appends entry 9 and the removal of entry 3.
        db.add(rng.integers(0, 256, size=(60, 32), dtype=np.uint8), "x" * (1100 << 10))
        db.add(rng.integers(0, 256, size=(60, 32), dtype=np.uint8), "l9")
        db.remove(3)
        counting[0] = True
        db.save_incremental(folder)
    else:
        db.add_many([rng.integers(0, 256, size=(60, 32), dtype=np.uint8) for _ in range(2)],
                    ["l8", "l9"])
        db.set_label(0, "first")
        counting[0] = True
        db.save(folder)
    counting[0] = False
print(calls[0])
"""


def sharded_state(db):
    """What a save holds: the next id and every live entry's label."""
    return db.next_entry_id, {entry: db.label(entry) for entry in range(db.next_entry_id)
                              if entry in db}


def test_a_save_killed_at_any_point_leaves_the_previous_or_the_new_save(client, vocabulary,
                                                                        tmp_path):
    import os
    import shutil
    import subprocess
    import sys
    from concurrent.futures import ThreadPoolExecutor

    module = sharded_module()
    vocabulary_path = tmp_path / "vocabulary.bbw"
    vocabulary.save(vocabulary_path)
    images = random_images(31, 8)
    labels = [f"l{i}" for i in range(8)]
    sharded = module.ShardedDatabase(client, vocabulary, shards=2)
    sharded.add_many(images[:6], labels[:6])
    previous = tmp_path / "previous"
    sharded.save(previous)
    sharded.add_many(images[6:], labels[6:])
    sharded.save_incremental(previous)  # both shards have a journal
    assert len(list(previous.glob("*.journal"))) == 2
    (previous / "notes.txt").write_text("not binbow's", encoding="utf-8")
    (previous / "shard-0.gen1.bbdb.copy").write_text("not binbow's either", encoding="utf-8")
    old = sharded_state(sharded)
    new = {
        "incremental": (10, {**{i: f"l{i}" for i in range(8) if i != 3},
                             8: "x" * (1100 << 10), 9: "l9"}),
        "full": (10, {**{i: f"l{i}" for i in range(10)}, 0: "first"}),
    }

    def run(kind, kill_at):
        folder = tmp_path / f"{kind}-{kill_at}"
        shutil.copytree(previous, folder)
        result = subprocess.run([sys.executable, "-c", _KILLED_SAVE, str(folder),
                                 str(vocabulary_path), kind, str(kill_at)],
                                capture_output=True, text=True, timeout=120)
        return folder, result

    for kind in ("incremental", "full"):
        folder, result = run(kind, 0)  # never killed: how many calls change files
        assert result.returncode == 0, result.stderr
        calls = int(result.stdout.split()[-1])
        assert calls >= 3, result.stdout
        found = sharded_state(module.ShardedDatabase.load(client, folder, vocabulary))
        assert found == new[kind]
        outcomes = set()
        with ThreadPoolExecutor(2) as pool:  # the processes, two at a time
            runs = list(pool.map(lambda kill_at: run(kind, kill_at), range(1, calls + 1)))
        loaded, failures = {}, []
        for kill_at, (folder, result) in enumerate(runs, 1):
            assert result.returncode == -9, (kind, kill_at, result.stderr)
            try:
                loaded[kill_at] = module.ShardedDatabase.load(client, folder, vocabulary)
            except binbow.Error as error:
                failures.append(f"{kind} save killed at call {kill_at} of {calls}: {error}")
        assert not failures, "\n".join(failures)
        for kill_at, db in loaded.items():
            folder = runs[kill_at - 1][0]
            state = sharded_state(db)
            assert state in (old, new[kind]), (kind, kill_at)
            outcomes.add(state == old)
            # Loading removed what the killed save left, and nothing else.
            manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
            named = set(manifest["files"]) | {name + suffix for name in manifest["files"]
                                               for suffix in (".journal", ".lock")}
            assert sorted(p.name for p in folder.iterdir()) == sorted(
                named & set(os.listdir(folder)) | {"manifest.json", "notes.txt",
                                                   "shard-0.gen1.bbdb.copy"}), (kind, kill_at)
            # The loaded database saves on: the next incremental save commits.
            db.add(images[0], "after")
            db.save_incremental(folder)
            again = module.ShardedDatabase.load(client, folder, vocabulary)
            assert sharded_state(again)[1][state[0]] == "after"
        assert outcomes == {True, False}, f"{kind}: every kill left the same save"


def test_the_manifest_has_the_umask_s_permissions_and_reaches_the_disk_before_it_counts(
        client, vocabulary, tmp_path, monkeypatch):
    import os
    import stat

    sharded = sharded_module().ShardedDatabase(client, vocabulary, shards=2)
    sharded.add_many(random_images(32, 3))
    events = []
    fsync, replace = os.fsync, os.replace

    def recorded_fsync(descriptor):
        events.append(("fsync", os.readlink(f"/proc/self/fd/{descriptor}")))
        return fsync(descriptor)

    def recorded_replace(source, destination):
        events.append(("replace", os.fspath(source), os.fspath(destination)))
        return replace(source, destination)

    monkeypatch.setattr(os, "fsync", recorded_fsync)
    monkeypatch.setattr(os, "replace", recorded_replace)
    manifest = tmp_path / "manifest.json"
    for mask, mode in ((0o022, 0o644), (0o077, 0o600), (0o002, 0o664)):
        previous = os.umask(mask)
        try:
            sharded.save(tmp_path)
        finally:
            os.umask(previous)
        assert stat.S_IMODE(manifest.stat().st_mode) == mode, oct(mask)
    sharded.add(random_images(33, 1)[0])
    events.clear()
    previous = os.umask(0o002)
    try:
        sharded.save_incremental(tmp_path)
    finally:
        os.umask(previous)
    assert stat.S_IMODE(manifest.stat().st_mode) == 0o664
    # The temporary is flushed, renamed over the manifest, then the folder is flushed.
    [renamed] = [event for event in events if event[0] == "replace"]
    assert renamed[2] == str(manifest) and renamed[1].startswith(str(manifest) + ".tmp-")
    at = events.index(renamed)
    assert ("fsync", renamed[1]) in events[:at]
    assert ("fsync", str(tmp_path)) in events[at:]
    assert sorted(p.name for p in tmp_path.iterdir() if "tmp" in p.name) == []
