"""LoopDetector.save / LoopDetector.load (.bbld): a detector stopped, saved and resumed gives the
results of one never stopped; a state needs the vocabulary it ran with."""
import pytest

import binbow
from conftest import SOURCE_DIR, sample_frames


def _outcome(result):
    return (result.query, result.status, result.match, result.score, result.normalisation_score,
            result.island, result.consistent_queries, result.inliers.tolist())


@pytest.fixture(scope="module")
def orb_features():
    extractor = binbow.FeatureExtractor("orb")
    return [extractor.extract(path) for path in sample_frames()]


def _run(detector, features):
    return [_outcome(detector.process(k, d)) for k, d in features]


@pytest.mark.parametrize("kind", ["fixed", "online"])
def test_resumed_detector_equals_uninterrupted(kind, orb_features, tmp_path):
    vocabulary = binbow.Vocabulary.load(SOURCE_DIR / "data" / "vocab" / "orb_default.bbw")

    def make():
        if kind == "fixed":
            return binbow.LoopDetector(vocabulary)
        # The default, approximate search: its trees are saved with the state.
        return binbow.LoopDetector.online("orb")

    expected = _run(make(), orb_features)
    assert sum(status == "loop-detected" for _, status, *_ in expected) > 10

    first = make()
    resumed_results = _run(first, orb_features[:40])
    state = tmp_path / "state.bbld"
    first.save(state)
    resumed = binbow.LoopDetector.load(state, vocabulary if kind == "fixed" else None)
    assert len(resumed) == 40
    assert resumed.is_online == (kind == "online")
    resumed_results += _run(resumed, orb_features[40:])
    assert resumed_results == expected


def test_load_needs_the_vocabulary_it_ran_with(orb_features, tmp_path):
    orb = binbow.Vocabulary.load(SOURCE_DIR / "data" / "vocab" / "orb_default.bbw")
    brief = binbow.Vocabulary.load(SOURCE_DIR / "data" / "vocab" / "brief_default.bbw")
    detector = binbow.LoopDetector(orb)
    detector.process(*orb_features[0])
    state = tmp_path / "fixed.bbld"
    detector.save(str(state))
    with pytest.raises(OSError, match="different vocabulary"):
        binbow.LoopDetector.load(state, brief)
    with pytest.raises(OSError, match="load it with that vocabulary"):
        binbow.LoopDetector.load(state)
    online = tmp_path / "online.bbld"
    binbow.LoopDetector.online("orb").save(online)
    with pytest.raises(OSError, match="load it without a vocabulary"):
        binbow.LoopDetector.load(online, orb)
    state.write_bytes(b"BINBOWLD" + bytes(100))
    with pytest.raises(OSError, match="fixed.bbld"):
        binbow.LoopDetector.load(state, orb)
