"""binbow.LoopDetector.online and detect_loops(vocabulary="online"): no pre-trained vocabulary,
the same loops as `detect-loops --online-vocabulary`."""
import csv

import numpy as np
import pytest

import binbow
from conftest import SAMPLES, run_cli, sample_frames


@pytest.fixture(scope="module")
def cli_online_loops(tmp_path_factory):
    out = tmp_path_factory.mktemp("online") / "loops.csv"
    run_cli("detect-loops", "--online-vocabulary", "-o", out, SAMPLES / "samples")
    with open(out, newline="") as f:
        return [(int(row["query_index"]), int(row["match_index"])) for row in csv.DictReader(f)]


def test_online_detector_finds_the_cli_loops(cli_online_loops):
    extractor = binbow.FeatureExtractor()
    detector = binbow.LoopDetector.online("orb")
    assert detector.is_online
    results = [detector.process(k, d) for k, d in (extractor.extract(p) for p in sample_frames())]
    assert [(r.query, r.match) for r in results if r.detection] == cli_online_loops
    assert len(cli_online_loops) >= 37  # recall >= 0.85 of the 44 loop queries, if all right
    assert detector.word_count > 1000
    detector.clear()
    assert len(detector) == 0 and detector.word_count == 0


def test_detect_loops_online_equals_the_detector(cli_online_loops):
    results = binbow.detect_loops(SAMPLES / "samples", vocabulary="online")
    assert [(r.query, r.match) for r in results if r.detection] == cli_online_loops
    assert results.vocabulary == "online"


def test_online_arguments():
    assert binbow.LoopDetector.online(32, exact=True, new_word_distance=0.3).is_online
    with pytest.raises(TypeError, match="unknown vocabulary option 'new_word'"):
        binbow.LoopDetector.online("orb", new_word=0.3)
    with pytest.raises(TypeError, match="descriptor must be"):
        binbow.LoopDetector.online(2.5)
    with pytest.raises(ValueError):
        binbow.LoopDetector.online("orb", new_word_distance=1.5)
    with pytest.raises(ValueError):  # BRIEF's 32 bytes, not 16
        binbow.LoopDetector.online(16).process(np.zeros((2, 2)), np.zeros((2, 32), np.uint8))
