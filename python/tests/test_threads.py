"""The GIL is released around heavy calls, and concurrent use is safe."""
import sys
import threading
import time

import numpy as np
import pytest

import binbow
from conftest import clustered, sample_frames


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
    # Holding the GIL leaves the main thread ~0 iterations (switch interval 0.5 s);
    # a loaded machine still gives it hundreds when the GIL is released.
    assert iterations > 100, f"{name} held the GIL: {iterations} iterations in {seconds:.3f} s"


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


def test_extract_lets_other_threads_run():
    rng = np.random.default_rng(5)
    image = rng.integers(0, 256, size=(1500, 2000), dtype=np.uint8)
    extractor = binbow.FeatureExtractor("orb", max_features=5000)
    iterations, seconds = main_thread_progress_during(lambda: extractor.extract(image))
    assert seconds > 0.02, f"extract was too quick to tell: {seconds:.3f} s"
    assert iterations > 100, f"extract held the GIL: {iterations} iterations in {seconds:.3f} s"


def test_extractors_and_detectors_in_threads():
    frames = sample_frames()[:50]
    voc = binbow.Vocabulary.default("orb")
    shared = {name: binbow.FeatureExtractor(name) for name in ("orb", "brief", "brisk")}
    expected = {name: [e.extract(f)[1] for f in frames[:20]] for name, e in shared.items()}
    features = [shared["orb"].extract(f) for f in frames]
    sequential = []
    detector = binbow.LoopDetector(voc)
    for k, d in features:
        r = detector.process(k, d)
        sequential.append((r.status, r.match, r.inliers.tolist()))

    extracted = {}
    detected = [None] * 4
    failures = []

    def extract(name):
        try:
            extracted[name] = [shared[name].extract(f)[1] for f in frames[:20]]
        except BaseException as error:
            failures.append(error)

    def detect(slot):
        try:
            own = binbow.LoopDetector(voc)
            detected[slot] = [
                (r.status, r.match, r.inliers.tolist())
                for r in (own.process(k, d) for k, d in features)
            ]
        except BaseException as error:
            failures.append(error)

    threads = [threading.Thread(target=extract, args=(name,)) for name in shared]
    threads += [threading.Thread(target=detect, args=(slot,)) for slot in range(len(detected))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not failures, failures
    for name in shared:
        assert all((a == b).all() for a, b in zip(extracted[name], expected[name])), name
    assert all(d == sequential for d in detected)


def test_one_detector_shared_by_threads_is_serialised():
    frames = sample_frames()[:40]
    features = [binbow.FeatureExtractor().extract(f) for f in frames]
    detector = binbow.LoopDetector(binbow.Vocabulary.default("orb"))
    queries = []

    def feed(part):
        for k, d in part:
            queries.append(detector.process(k, d).query)

    threads = [threading.Thread(target=feed, args=(features[i::4],)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(detector) == len(frames)
    assert sorted(queries) == list(range(len(frames)))


def test_process_lets_other_threads_run(many_descriptors):
    detector = binbow.LoopDetector(binbow.Vocabulary.default("orb"))
    keypoints = np.random.default_rng(2).random((len(many_descriptors), 2), dtype=np.float32)
    iterations, seconds = main_thread_progress_during(
        lambda: detector.process(keypoints * 500, many_descriptors))
    assert seconds > 0.02, f"process was too quick to tell: {seconds:.3f} s"
    assert iterations > 100, f"process held the GIL: {iterations} in {seconds:.3f} s"
