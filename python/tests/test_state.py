"""LoopDetector.save / LoopDetector.load (.bbld): a detector stopped, saved and resumed gives the
results of one never stopped; a state needs the vocabulary it ran with."""
import numpy as np
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


@pytest.mark.parametrize("kind", ["fixed", "online"])
def test_detect_loops_saves_and_resumes_as_the_cli(kind, tmp_path):
    """detect_loops(save_state=) over frames 1..42, then (resume_state=) over 43..84: the
    loops of one run over 1..84; the kind and descriptor come from the state."""
    frames = sample_frames()
    vocabulary = "online" if kind == "online" else None
    state = tmp_path / "new folder" / f"{kind}.bbld"
    whole = binbow.detect_loops(frames, vocabulary)
    first = binbow.detect_loops(frames[:42], vocabulary, save_state=state)
    assert state.is_file() and first.resumed_from is None and first.resumed_frames == 0
    second = binbow.detect_loops(frames[42:], resume_state=state)
    assert second.resumed_from == str(state) and second.resumed_frames == 42
    assert second.descriptor == "orb"
    assert (second.vocabulary == "online") == (kind == "online")
    outcomes = [_outcome(r) + (r.file, r.match_file) for r in list(first) + list(second)]
    assert sum(r.detection for r in second) > 5
    assert outcomes == [_outcome(r) + (r.file, r.match_file) for r in whole]


def test_detect_loops_resume_state_contradictions(tmp_path):
    frames = sample_frames()[:3]
    fixed, online = tmp_path / "fixed.bbld", tmp_path / "online.bbld"
    binbow.detect_loops(frames, save_state=fixed)
    binbow.detect_loops(frames, "online", save_state=online)
    vocabulary = binbow.Vocabulary.load(SOURCE_DIR / "data" / "vocab" / "orb_default.bbw")
    with pytest.raises(ValueError, match="fixed vocabulary's state"):
        binbow.detect_loops(frames, "online", resume_state=fixed)
    with pytest.raises(ValueError, match="online vocabulary's state"):
        binbow.detect_loops(frames, vocabulary, resume_state=online)
    with pytest.raises(ValueError, match="run with orb descriptors, not brief"):
        binbow.detect_loops(frames, descriptor="brief", resume_state=fixed)
    with pytest.raises(ValueError, match="params must be None"):
        binbow.detect_loops(frames, params=binbow.LoopDetectorParams(), resume_state=fixed)
    with pytest.raises(TypeError, match="resume_state must be a path"):
        binbow.detect_loops(frames, resume_state=3)
    with pytest.raises(OSError, match="is a folder, not a file"):
        binbow.detect_loops(frames, save_state=tmp_path)
    with pytest.raises(OSError, match="missing.bbld"):
        binbow.detect_loops(frames, resume_state=tmp_path / "missing.bbld")
    # The vocabulary it ran with is accepted as well as None.
    assert len(binbow.detect_loops(frames, vocabulary, resume_state=fixed)) == 3


def test_forgotten_frames_stay_forgotten_across_save_and_resume(orb_features, tmp_path):
    """Keyframe culling: the frames the loops so far matched are forgotten at frame 60; no later
    frame proposes them (the detector that keeps them does), and forget + save + load (or
    detect_loops' resume_state) continues exactly as forget + continue."""
    vocabulary = binbow.Vocabulary.load(SOURCE_DIR / "data" / "vocab" / "orb_default.bbw")
    reference = _run(binbow.LoopDetector(vocabulary), orb_features)
    stop = 60
    culled = sorted({m for _, status, m, *_ in reference[:stop] if status == "loop-detected"})
    assert len(culled) >= 3
    assert any(match in culled for _, _, match, *_ in reference[stop:]), "kept, they come back"

    continued = binbow.LoopDetector(vocabulary)
    _run(continued, orb_features[:stop])
    memory = continued.memory_usage
    for frame in culled:
        continued.forget(frame)
    continued.forget(culled[0])  # already forgotten: nothing happens
    assert continued.memory_usage < memory
    assert continued.forgotten_count == len(culled) and len(continued) == stop
    assert [continued.is_forgotten(f) for f in range(stop)] == [f in culled for f in range(stop)]
    state = tmp_path / "culled.bbld"
    continued.save(state)
    resumed = binbow.LoopDetector.load(state, vocabulary)
    assert resumed.forgotten_count == len(culled)

    later = _run(continued, orb_features[stop:])
    assert _run(resumed, orb_features[stop:]) == later
    assert all(match not in culled for _, _, match, *_ in later)
    assert sum(status == "loop-detected" for _, status, *_ in later) > 5
    # detect_loops resumes it as the CLI's --resume-state does.
    frames = sample_frames()[stop:]
    assert [_outcome(r) for r in binbow.detect_loops(frames, resume_state=state)] == later


def test_forget_takes_frame_ids_strictly(orb_features):
    detector = binbow.LoopDetector.online("orb")
    _run(detector, orb_features[:3])
    for wrong in (1.0, True, "1", None):
        with pytest.raises(TypeError, match="frame must be an int"):
            detector.forget(wrong)
    for missing in (-1, 3, 2**32, 2**70):
        with pytest.raises(ValueError):
            detector.forget(missing)
        with pytest.raises(ValueError):
            detector.is_forgotten(missing)
    assert detector.forgotten_count == 0
    detector.forget(np.int64(1))
    assert detector.is_forgotten(1) and not detector.is_forgotten(np.uint8(2))
    assert detector.process(*orb_features[3]).query == 3
