"""binbow.detect_loops and binbow.write_report: the CLI's detect-loops from Python."""
import csv
import html
import json
import pathlib
import pickle
import re
import shlex
import sys

import numpy as np
import pytest

import binbow
from conftest import SAMPLES, run_cli, sample_frames

FOLDER = SAMPLES / "samples"


def csv_rows(path):
    with open(path, newline="", encoding="utf-8") as file:
        return list(csv.DictReader(file))


def as_rows(results):
    """The loops.csv rows detect-loops would write for these results."""
    return [
        (str(r.query), str(r.match), r.file, r.match_file, r.normalised_score, str(len(r.inliers)))
        for r in results if r.detection
    ]


def assert_same_loops(results, rows):
    found = as_rows(results)
    expected = [(row["query_index"], row["match_index"], row["query_file"], row["match_file"],
                 float(row["score"]), row["inliers"]) for row in rows]
    assert [f[:4] + f[5:] for f in found] == [e[:4] + e[5:] for e in expected]
    np.testing.assert_allclose([f[4] for f in found], [e[4] for e in expected], rtol=1e-5)


@pytest.fixture(scope="module")
def results():
    return binbow.detect_loops(FOLDER)


def test_finds_exactly_the_cli_loops(results, cli_loops):
    _, rows = cli_loops
    assert len(results) == 84 and isinstance(results, list)
    assert_same_loops(results, rows)
    assert [r.file for r in results] == [str(p) for p in sample_frames()]
    assert all(r.times["features"] > 0 for r in results)
    assert all((r.match_file != "") == r.detection for r in results)


def test_the_run_is_described(results):
    assert results.params == binbow.LoopDetectorParams()
    assert results.descriptor == "orb" and results.inputs == [str(FOLDER)]
    assert results.vocabulary.checksum == binbow.Vocabulary.default("orb").checksum
    assert results.vocabulary_file.endswith("orb_default.bbw")


@pytest.mark.parametrize(
    "python, cli",
    [
        ({"descriptor": "brief"}, ["--descriptor", "brief"]),
        ({"stride": 2, "max_width": 256}, ["--stride", "2", "--max-width", "256"]),
        ({"max_features": 500}, ["--features", "500"]),
    ],
)
def test_options_as_the_cli(tmp_path, python, cli):
    output = tmp_path / "loops.csv"
    run_cli("detect-loops", *cli, "-o", output, FOLDER)
    assert_same_loops(binbow.detect_loops(FOLDER, **python), csv_rows(output))


def test_params_objects_and_files_as_the_cli(tmp_path):
    params_file = tmp_path / "params.json"
    params_file.write_text(json.dumps({"dislocal": 10, "alpha": 0.2, "k": 2}))
    output = tmp_path / "loops.csv"
    run_cli("detect-loops", "--params", params_file, "-o", output, FOLDER)
    expected = csv_rows(output)
    from_file = binbow.detect_loops(FOLDER, params=params_file)
    assert_same_loops(from_file, expected)
    assert from_file.params == binbow.LoopDetectorParams(dislocal=10, alpha=0.2, k=2)
    from_object = binbow.detect_loops([str(FOLDER)], params=from_file.params)
    assert_same_loops(from_object, expected)


def test_inputs_lists_and_extractors(tmp_path, results):
    listing = tmp_path / "frames.txt"
    listing.write_text("\n".join(str(p) for p in sample_frames()) + "\n")
    assert as_rows(binbow.detect_loops(listing)) == as_rows(results)
    assert as_rows(binbow.detect_loops(sample_frames())) == as_rows(results)
    extractor = binbow.FeatureExtractor("orb")
    assert as_rows(binbow.detect_loops(FOLDER, descriptor=extractor)) == as_rows(results)
    few = binbow.detect_loops(sample_frames()[:30], descriptor=binbow.FeatureExtractor("brief"))
    assert len(few) == 30 and few.descriptor == "brief"


def test_progress(capfd):
    calls = []
    binbow.detect_loops(sample_frames()[:12], progress=lambda done, total: calls.append((done, total)))
    assert calls == [(done, 12) for done in range(1, 13)]
    binbow.detect_loops(FOLDER, progress=True)
    printed = capfd.readouterr().err
    # Not a terminal: no redraws, and a run of a second logs only its closing line.
    assert "\r" not in printed and "\033" not in printed
    assert "detecting loops: 42/84" not in printed
    assert re.search(r"^detecting loops: 84 done in [0-9.]+s$", printed, re.M), printed


def test_a_raising_progress_stops_the_run():
    seen = []

    def stop(done, total):
        seen.append(done)
        if done == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        binbow.detect_loops(FOLDER, progress=stop)
    assert seen == [1, 2, 3]


def test_strict_arguments(tmp_path):
    with pytest.raises(OSError, match="missing"):
        binbow.detect_loops(tmp_path / "missing")
    with pytest.raises(ValueError, match="no default vocabulary for descriptor 'akaze'"):
        binbow.detect_loops(FOLDER, descriptor="akaze")
    with pytest.raises(ValueError, match="akaze"):
        binbow.detect_loops(FOLDER, vocabulary=binbow.Vocabulary.default("orb"),
                            descriptor="akaze")
    with pytest.raises(ValueError, match="unknown feature type"):
        binbow.detect_loops(FOLDER, vocabulary=binbow.Vocabulary.default("orb"),
                            descriptor="sift")
    with pytest.raises(TypeError, match=r"inputs\[1\]"):
        binbow.detect_loops([FOLDER, 3])
    with pytest.raises(TypeError, match="progress"):
        binbow.detect_loops(FOLDER, progress="yes")
    with pytest.raises(TypeError, match="params"):
        binbow.detect_loops(FOLDER, params={"alpha": 0.3})
    with pytest.raises(ValueError, match="stride"):
        binbow.detect_loops(FOLDER, stride=0)
    with pytest.raises(TypeError, match="max_features must be an int"):
        binbow.detect_loops(FOLDER, max_features=10.0)
    with pytest.raises(ValueError, match="FeatureExtractor has its own"):
        binbow.detect_loops(FOLDER, descriptor=binbow.FeatureExtractor(), max_features=10)
    bad = tmp_path / "bad.json"
    bad.write_text('{"alpha": -1}')
    with pytest.raises(OSError, match="bad.json"):
        binbow.detect_loops(FOLDER, params=bad)


def report_facts(page):
    text = page.read_text(encoding="utf-8")
    return dict(re.findall(r"<tr><th>([^<]*)</th><td>([^<]*)</td></tr>", text)), text


def test_write_report_draws_the_cli_page(tmp_path, results):
    cli_page = tmp_path / "cli" / "index.html"
    run_cli("detect-loops", "--report", cli_page.parent, "-o", tmp_path / "loops.csv", FOLDER)
    page = binbow.write_report(tmp_path / "python", results)
    assert page == str(tmp_path / "python" / "index.html")
    cli_facts, cli_text = report_facts(cli_page)
    facts, text = report_facts(tmp_path / "python" / "index.html")
    assert cli_facts.keys() == facts.keys()
    for key in ("inputs", "frames", "loops", "frequency", "descriptor"):
        assert facts[key] == cli_facts[key], key
    headings = re.compile(r"<h2[^>]*>([^<]*)")
    assert headings.findall(text) == headings.findall(cli_text)
    assert text.count("data:image/") == cli_text.count("data:image/") > 0


def test_write_report_says_who_wrote_it_when_and_how(tmp_path, results):
    _, text = report_facts(pathlib.Path(binbow.write_report(tmp_path / "r", results)))
    match = re.search(r"<p class='provenance' id='provenance'>Written by binbow (\S+) on "
                      r"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ): <code>([^<]*)</code>", text)
    assert match, text[:2000]
    assert match.group(1) == binbow.__version__
    assert shlex.split(html.unescape(match.group(3)))[1:] == sys.argv


def test_write_report_with_ground_truth_and_plain_lists(tmp_path, results):
    truth = binbow.GroundTruth.load(SAMPLES / "samples_GT_pairs.txt")
    binbow.write_report(tmp_path / "evaluated", results, truth)
    _, text = report_facts(tmp_path / "evaluated" / "index.html")
    assert "Precision and recall" in text
    plain = binbow.write_report(str(tmp_path / "plain"), list(results))
    facts, text = report_facts(tmp_path / "plain" / "index.html")
    assert facts["loops"] == "40" and "Parameters" not in text, "unknown parameters not shown"
    assert plain.endswith("index.html")
    with pytest.raises(TypeError, match="LoopResult"):
        binbow.write_report(tmp_path / "bad", [1, 2])


def test_the_similarity_matrix_comes_with_the_results(tmp_path, results):
    similarity = results.similarity
    assert (similarity.frames, similarity.bin, similarity.cells) == (84, 1, 84)
    scores = similarity.scores
    assert scores.dtype == np.float32 and scores.shape == (84, 84)
    assert not np.triu(scores).any(), "only earlier images are scored"
    # A detected loop is among the most similar earlier images of its query.
    loop = next(r for r in results if r.detection)
    assert scores[loop.query, loop.match] >= np.sort(scores[loop.query])[-5] > 0
    again = pickle.loads(pickle.dumps(similarity))
    assert np.array_equal(again.scores, scores) and again.frames == 84
    binbow.write_report(tmp_path / "report", results)
    assert (tmp_path / "report" / "similarity.png").stat().st_size > 1000


def test_skip_unreadable_keeps_the_frame_numbers_as_the_cli(tmp_path):
    frames = sorted(FOLDER.glob("*.jpg"), key=lambda p: int(p.stem))
    truncated = tmp_path / "50.jpg"
    truncated.write_bytes(frames[49].read_bytes()[: frames[49].stat().st_size // 2])
    listed = [str(truncated) if i == 49 else str(p) for i, p in enumerate(frames)]
    frame_list = tmp_path / "frames.txt"
    frame_list.write_text("\n".join(listed) + "\n")

    with pytest.raises(OSError, match=re.escape(str(truncated))):
        binbow.detect_loops(frame_list)
    with pytest.warns(UserWarning, match=re.escape(str(truncated)) + ": damaged JPEG"):
        skipped = binbow.detect_loops(frame_list, skip_unreadable=True)
    assert [r.file for r in skipped] == listed
    assert [r.query for r in skipped] == list(range(len(listed)))
    assert skipped[49].status == "unreadable" and skipped[49].unreadable.startswith("damaged JPEG")
    assert all(r.status != "unreadable" and not r.unreadable for i, r in enumerate(skipped) if i != 49)
    assert pickle.loads(pickle.dumps(skipped[49])).status == "unreadable"
    loops = [r for r in skipped if r.detection]
    assert loops and all(listed[r.match] == r.match_file for r in loops)

    run_cli("detect-loops", "--skip-unreadable", "-o", str(tmp_path / "loops.csv"), str(frame_list))
    assert_same_loops(skipped, csv_rows(tmp_path / "loops.csv"))


def test_any_number_of_threads_gives_one_threads_results(tmp_path, results):
    one = binbow.detect_loops(FOLDER, threads=1, save_state=tmp_path / "one.bbld")
    many = binbow.detect_loops(FOLDER, threads=3, save_state=tmp_path / "many.bbld")
    assert len(as_rows(one)) > 5, "too few loops to compare"
    for run in (many, results):  # results: every core
        assert as_rows(run) == as_rows(one)
        assert [(r.status, r.score, r.island_score, r.file) for r in run] == [
            (r.status, r.score, r.island_score, r.file) for r in one
        ]
    assert (tmp_path / "many.bbld").read_bytes() == (tmp_path / "one.bbld").read_bytes()
    # Stopped early, the threads reading ahead are joined: no hang.
    seen = []

    def stop(done, total):
        seen.append(done)
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        binbow.detect_loops(FOLDER, progress=stop, threads=4)
    assert seen == [1, 2]
    with pytest.raises(ValueError, match="threads"):
        binbow.detect_loops(FOLDER, threads=-1)
    with pytest.raises(ValueError, match="threads"):
        binbow.detect_loops(FOLDER, threads=100_000)
