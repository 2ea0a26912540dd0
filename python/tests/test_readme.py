"""The README's Python example runs as written, from the source tree, on the bundled sample."""
import re
import subprocess
import sys

from conftest import SOURCE_DIR


def readme_python_example():
    readme = (SOURCE_DIR / "README.md").read_text(encoding="utf-8")
    section = readme.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(blocks) == 1, "the README's Python section should have one python example"
    return blocks[0]


def test_readme_example_finds_the_first_pass_of_the_corridor():
    result = subprocess.run([sys.executable, "-c", readme_python_example()], cwd=SOURCE_DIR,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 3, result.stdout
    # Frame 61 is the corridor's second pass; the ground truth pairs it with 19-23.
    truth = {
        int(match)
        for line in (SOURCE_DIR / "data/samples/rtabmap/samples_GT_pairs.txt").read_text().splitlines()
        if line.startswith("61 ")
        for match in line.split()[1:]
    }
    best = int(re.search(r"samples/(\d+)\.jpg", lines[0]).group(1))
    assert best in truth, (best, truth, result.stdout)
