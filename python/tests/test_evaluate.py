"""binbow.GroundTruth and binbow.evaluate: the numbers of the CLI's evaluate."""
import re

import pytest

import binbow
from conftest import SAMPLES, run_cli, sample_frames

PAIRS = SAMPLES / "samples_GT_pairs.txt"
MATRIX = SAMPLES / "samples_GT.bmp"


@pytest.fixture(scope="module")
def results():
    extractor = binbow.FeatureExtractor()
    detector = binbow.LoopDetector(binbow.Vocabulary.default("orb"))
    return [detector.process(*extractor.extract(path)) for path in sample_frames()]


def cli_numbers(loops_csv, ground_truth):
    printed = run_cli("evaluate", "--gt", ground_truth, loops_csv).stdout
    numbers = dict(re.findall(r"^([a-z ]+): ([0-9.e+-]+)$", printed, re.M))
    # The lists of misses and false loops after the summary.
    numbers.pop("missed loops", None)
    numbers.pop("false loops", None)
    assert len(numbers) == 7, printed
    return numbers


def test_ground_truth_formats_agree():
    pairs = binbow.GroundTruth.load(PAIRS)
    matrix = binbow.GroundTruth.load(str(MATRIX))
    assert pairs.frames == matrix.frames == 84
    assert pairs.queries_with_loops == matrix.queries_with_loops > 0
    for query in range(84):
        assert pairs.has_loop(query) == matrix.has_loop(query)
        assert pairs.earlier_matches(query) == matrix.earlier_matches(query)
    assert 19 in pairs.earlier_matches(60) and pairs.is_loop(60, 19) and pairs.is_loop(19, 60)
    assert "84 frames" in repr(pairs)
    assert binbow.GroundTruth.load(MATRIX, frames=40).frames == 40


def test_ground_truth_base_and_pairs(tmp_path):
    text = tmp_path / "pairs.txt"
    text.write_text("3 1\n4 2\n")
    with pytest.raises(OSError, match="pairs.txt"):
        binbow.GroundTruth.load(text)  # neither a base comment nor an index 0
    zero = binbow.GroundTruth.load(text, base=0)
    one = binbow.GroundTruth.load(text, base=1)
    assert zero.is_loop(3, 1) and one.is_loop(2, 0)
    with pytest.raises(ValueError, match="base"):
        binbow.GroundTruth.load(text, base=2)
    made = binbow.GroundTruth(5, [(3, 1), (4, 2)])
    assert made.frames == 5 and made.pair_count == 2 and made.queries_with_loops == 2
    assert [made.has_loop(q) for q in range(5)] == [False, False, False, True, True]
    # Consecutive earlier frames are one range, [first, end).
    block = binbow.GroundTruth(9, [(8, 1), (8, 2), (8, 3), (8, 6), (2, 8)])
    assert block.earlier_match_ranges(8) == [(1, 4), (6, 7)]
    assert block.earlier_matches(8) == [1, 2, 3, 6]
    assert block.range_count == 2 and block.pair_count == 4
    with pytest.raises(ValueError):
        binbow.GroundTruth(3, [(5, 1)])


@pytest.mark.parametrize("ground_truth", [PAIRS, MATRIX])
def test_evaluate_gives_the_cli_numbers(results, cli_loops, ground_truth):
    loops_csv, _ = cli_loops
    expected = cli_numbers(loops_csv, ground_truth)
    truth = binbow.GroundTruth.load(ground_truth)
    for evaluation in (binbow.evaluate(results, truth), binbow.evaluate(loops_csv, truth),
                       binbow.evaluate(str(loops_csv), truth)):
        assert evaluation.precision == pytest.approx(float(expected["precision"]), rel=1e-5)
        assert evaluation.recall == pytest.approx(float(expected["recall"]), rel=1e-5)
        assert evaluation.detections == int(expected["detections"])
        assert evaluation.true_positives == int(expected["true positives"])
        assert evaluation.false_positives == int(expected["false positives"])
        assert evaluation.queries_with_loops == int(expected["queries with a loop"])
        assert evaluation.queries_found == int(expected["queries found"])


def test_verdicts(results):
    truth = binbow.GroundTruth(84, [(60, 19), (61, 21), (83, 5)])
    evaluation = binbow.evaluate(results, truth)
    detections = [(r.query, r.match) for r in results if r.detection]
    assert [v[:2] for v in evaluation.verdicts] == detections
    assert [v[2] for v in evaluation.verdicts] == [truth.is_loop(q, m) for q, m in detections]
    assert sum(v[2] for v in evaluation.verdicts) == evaluation.true_positives
    assert evaluation.query_verdicts == {60: True, 61: True, 83: False}
    assert evaluation.queries_found == 2 and evaluation.recall == pytest.approx(2 / 3)
    assert "precision" in repr(evaluation)


def test_evaluate_strict_arguments(results):
    small = binbow.GroundTruth(10, [(5, 1)])
    with pytest.raises(ValueError):
        binbow.evaluate(results, small)  # detections beyond frame 9
    with pytest.raises(TypeError, match="LoopResult"):
        binbow.evaluate([(40, 1)], small)
    with pytest.raises(TypeError, match="int"):
        binbow.evaluate(3, small)
    with pytest.raises(OSError, match="missing.csv"):
        binbow.evaluate("missing.csv", small)
    nothing = binbow.evaluate([], small)
    assert (nothing.precision, nothing.recall, nothing.detections) == (1.0, 0.0, 0)
    assert nothing.query_verdicts == {5: False}
