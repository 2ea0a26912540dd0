"""binbow.LoopDetector and LoopResult: the CLI's loops, strict inputs, every field."""
import pickle

import numpy as np
import pytest

import binbow
from conftest import require_module, sample_frames

STATUSES = {
    "loop-detected", "no-database-results", "low-normalisation-score", "low-scores",
    "no-islands", "no-temporal-consistency", "no-geometric-consistency",
}


@pytest.fixture(scope="module")
def features():
    extractor = binbow.FeatureExtractor()
    return [extractor.extract(path) for path in sample_frames()]


@pytest.fixture(scope="module")
def results(features):
    detector = binbow.LoopDetector(binbow.Vocabulary.default("orb"))
    out = [detector.process(k, d) for k, d in features]
    assert len(detector) == len(features)
    return out


def test_finds_exactly_the_cli_loops(results, cli_loops):
    _, rows = cli_loops
    found = [(r.query, r.match, r.normalised_score, len(r.inliers)) for r in results if r.detection]
    expected = [(int(row["query_index"]), int(row["match_index"]), float(row["score"]),
                 int(row["inliers"])) for row in rows]
    assert [f[:2] for f in found] == [e[:2] for e in expected]
    assert [f[3] for f in found] == [e[3] for e in expected]
    np.testing.assert_allclose([f[2] for f in found], [e[2] for e in expected], rtol=1e-5)


def test_result_fields(results, features):
    assert [r.query for r in results] == list(range(len(results)))
    assert {r.status for r in results} <= STATUSES
    assert results[0].status == "no-database-results" and results[0].match is None
    assert results[0].island is None and results[0].file == ""
    loops = [r for r in results if r.detection]
    assert loops and all(r.status == "loop-detected" for r in loops)
    for r in loops:
        assert r.match < r.query and r.score > 0 and r.normalised_score > 0
        first, last = r.island
        assert first <= r.match <= last
        assert r.consistent_queries >= 1 and r.correspondences >= len(r.inliers)
        assert r.inliers.dtype == np.int64 and r.inliers.shape == (len(r.inliers), 2)
        assert len(r.inliers) >= binbow.LoopDetectorParams().min_inliers
        query_points, _ = features[r.query]
        match_points, _ = features[r.match]
        np.testing.assert_array_equal(r.inlier_points[:, :2], query_points[r.inliers[:, 0], :2])
        np.testing.assert_array_equal(r.inlier_points[:, 2:], match_points[r.inliers[:, 1], :2])
        assert set(r.times) == {"features", "transform", "query", "islands", "verification",
                                "insertion"}
        assert r.times["features"] == 0 and r.times["verification"] > 0
        assert f"query {r.query}" in repr(r) and "loop-detected" in repr(r)
    undetected = [r for r in results if not r.detection]
    assert all(r.inlier_points.shape == (0, 4) for r in undetected)
    # A failed geometric check still tells how many correspondences it tried.
    assert any(r.correspondences for r in undetected if r.status == "no-geometric-consistency")


def test_keypoint_forms_give_the_same_loops(features, results):
    cv2 = require_module("cv2", "python3-opencv")
    voc = binbow.Vocabulary.default("orb")
    xy = binbow.LoopDetector(voc)
    opencv = binbow.LoopDetector(voc)
    for (k, d), expected in zip(features, results):
        as_xy = xy.process(k[:, :2].astype(np.float64), d)
        keypoints = [cv2.KeyPoint(float(x), float(y), float(s), float(a), float(r), int(o))
                     for x, y, s, a, r, o in k]
        as_opencv = opencv.process(tuple(keypoints), d)
        for got in (as_xy, as_opencv):
            assert (got.status, got.match) == (expected.status, expected.match)
            np.testing.assert_array_equal(got.inliers, expected.inliers)


def test_images_without_features(features):
    detector = binbow.LoopDetector(binbow.Vocabulary.default("orb"))
    assert detector.process(None, None).status == "no-database-results"
    assert detector.process(np.zeros((0, 6), np.float32), None).query == 1
    assert detector.process([], np.zeros((0, 32), np.uint8)).query == 2
    detector.process(*features[0])
    assert len(detector) == 4
    detector.clear()
    assert len(detector) == 0 and detector.process(*features[1]).query == 0


def test_strict_inputs(features):
    keypoints, descriptors = features[0]
    detector = binbow.LoopDetector(binbow.Vocabulary.default("orb"))
    with pytest.raises(TypeError, match="int32"):
        detector.process(keypoints.astype(np.int32), descriptors)
    with pytest.raises(TypeError, match="float16"):
        detector.process(keypoints.astype(np.float16), descriptors)
    with pytest.raises(ValueError, match=r"\(N, 6\).*got shape \(512, 3\)"):
        detector.process(keypoints[:, :3], descriptors)
    with pytest.raises(ValueError, match="one keypoint per descriptor"):
        detector.process(keypoints[:-1], descriptors)
    with pytest.raises(ValueError, match="one keypoint per descriptor"):
        detector.process(None, descriptors)
    with pytest.raises(TypeError, match="float32"):
        detector.process(keypoints, descriptors.astype(np.float32))
    with pytest.raises(ValueError, match="bytes"):
        detector.process(keypoints, descriptors[:, :16])
    with pytest.raises(TypeError, match="str"):
        detector.process("keypoints", descriptors)
    nan = keypoints.copy()
    nan[3, 0] = np.nan
    with pytest.raises(ValueError, match=r"keypoints\[3\]"):
        detector.process(nan, descriptors)
    for octave in (np.inf, 1e12, 2.5):
        odd = keypoints.copy()
        odd[7, 5] = octave
        with pytest.raises(ValueError, match=r"keypoints\[7\] has octave"):
            detector.process(odd, descriptors)
    assert len(detector) == 0, "refused inputs add nothing"
    strided = np.asfortranarray(keypoints)
    assert detector.process(strided, np.asfortranarray(descriptors)).query == 0


def test_params_are_used_and_kept(features):
    voc = binbow.Vocabulary.default("orb")
    params = binbow.LoopDetectorParams(dislocal=200)
    detector = binbow.LoopDetector(voc, params)
    assert detector.params == params and detector.vocabulary.checksum == voc.checksum
    assert not any(detector.process(k, d).detection for k, d in features)
    none = binbow.LoopDetector(voc, binbow.LoopDetectorParams(geometric_check="none"))
    loops = [r for r in (none.process(k, d) for k, d in features) if r.detection]
    assert loops and all(len(r.inliers) == 0 for r in loops)
    with pytest.raises(TypeError):
        binbow.LoopDetector(voc, {"alpha": 0.3})


def test_results_count_the_features_of_each_image(features, results):
    assert [r.features for r in results] == [len(k) for k, _ in features]
    assert pickle.loads(pickle.dumps(results[3])).features == results[3].features
