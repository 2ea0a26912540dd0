"""The README's Python examples run as written, on the bundled sample.

They use paths relative to the repository's root and write report/ there, so
they run in a temporary folder whose data/ is the repository's.
"""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import binbow
from conftest import SAMPLES, SOURCE_DIR


def readme_python_examples():
    readme = (SOURCE_DIR / "README.md").read_text(encoding="utf-8")
    section = readme.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(blocks) == 2, "the README's Python section should have two python examples"
    return blocks


@pytest.fixture()
def root(tmp_path):
    (tmp_path / "data").symlink_to(SOURCE_DIR / "data")
    return tmp_path


def run(example, cwd):
    # The package under test, wherever the working folder is.
    package_parent = str(Path(binbow.__file__).resolve().parents[1])
    environment = dict(os.environ, PYTHONPATH=package_parent)
    result = subprocess.run([sys.executable, "-c", example], cwd=cwd, env=environment,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    return result.stdout.splitlines()


def test_loop_detection_example(root):
    lines = run(readme_python_examples()[0], root)
    assert len(lines) == 3, lines
    assert lines[0] == "40 loops, precision 1.000, recall 0.909"
    assert re.fullmatch(r"60 closes a loop with 19: \d+ inliers", lines[1]), lines
    assert re.fullmatch(r"61 closes a loop with 21: \d+ inliers", lines[2]), lines
    page = root / "report" / "index.html"
    assert page.is_file() and page.stat().st_size > 10_000


def test_database_example_finds_the_first_pass_of_the_corridor(root):
    lines = run(readme_python_examples()[1], root)
    assert len(lines) == 3, lines
    # Frame 61 is the corridor's second pass; the ground truth pairs it with 19-23.
    truth = {
        int(match)
        for line in (SAMPLES / "samples_GT_pairs.txt").read_text().splitlines()
        if line.startswith("61 ")
        for match in line.split()[1:]
    }
    best = int(re.search(r"samples/(\d+)\.jpg", lines[0]).group(1))
    assert best in truth, (best, truth, lines)
