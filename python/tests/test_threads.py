"""The GIL is released around heavy calls, and concurrent use is safe."""
import sys
import threading
import time

import numpy as np
import pytest

import binbow
from conftest import clustered


def main_thread_progress_during(call):
    """Loop iterations of this thread while `call` runs in another one.

    While a call holds the GIL no other Python thread runs, so the count stays
    zero; with the GIL released this thread keeps looping. A long switch
    interval keeps the interpreter from handing the GIL over in between.
    """
    in_call = [False]
    finished = threading.Event()
    failure = []

    def run():
        try:
            in_call[0] = True
            call()
            in_call[0] = False
        except BaseException as error:  # reported below, in the test's thread
            failure.append(error)
        finished.set()

    worker = threading.Thread(target=run)
    interval = sys.getswitchinterval()
    sys.setswitchinterval(0.5)
    try:
        start = time.monotonic()
        worker.start()
        iterations = 0
        while not finished.is_set():
            if in_call[0]:
                iterations += 1
        worker.join()
    finally:
        sys.setswitchinterval(interval)
    if failure:
        raise failure[0]
    return iterations, time.monotonic() - start


@pytest.fixture(scope="module")
def many_descriptors():
    return np.random.default_rng(11).integers(0, 256, size=(300_000, 32), dtype=np.uint8)


@pytest.mark.parametrize(
    "name", ["transform", "transform_with_features", "quantize", "Database.add", "build"]
)
def test_heavy_calls_let_other_threads_run(name, many_descriptors):
    voc = binbow.Vocabulary.default("orb")
    calls = {
        "transform": lambda: voc.transform(many_descriptors),
        "transform_with_features": lambda: voc.transform_with_features(many_descriptors),
        "quantize": lambda: voc.quantize(many_descriptors),
        "Database.add": lambda: binbow.Database(voc).add(many_descriptors),
        "build": lambda: binbow.Vocabulary.build(
            [many_descriptors[:50_000]], branching=10, levels=3, threads=1, weighting="tf"
        ),
    }
    iterations, seconds = main_thread_progress_during(calls[name])
    assert seconds > 0.02, f"{name} was too quick to tell: {seconds:.3f} s"
    assert iterations > 1000, f"{name} held the GIL: {iterations} iterations in {seconds:.3f} s"


def test_queries_and_adds_from_many_threads():
    rng = np.random.default_rng(3)
    images = [clustered(rng, 200) for _ in range(40)]
    voc = binbow.Vocabulary.build(images, branching=6, levels=3, seed=1)
    db = binbow.Database(voc)
    for image in images[:20]:
        db.add(image)
    bows = [voc.transform(image) for image in images[:20]]
    expected = [db.query(b, 3, max_entry_id=19) for b in bows]
    results = [None] * len(bows)

    def query(i):
        results[i] = db.query(bows[i], 3, max_entry_id=19)

    def add(i):
        db.add(images[20 + i], label=f"late {i}")

    threads = [threading.Thread(target=query, args=(i,)) for i in range(len(bows))]
    threads += [threading.Thread(target=add, args=(i,)) for i in range(20)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert results == expected
    assert len(db) == 40
    assert sorted(db.label(e) for e in range(20, 40)) == sorted(f"late {i}" for i in range(20))
