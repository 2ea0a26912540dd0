"""python/examples run on the bundled sample."""
import subprocess
import sys

from conftest import SAMPLES, SOURCE_DIR, require_module

EXAMPLES = SOURCE_DIR / "python" / "examples"


def test_detect_and_plot_draws_the_similarity_matrix(tmp_path):
    image = require_module("matplotlib.image", "python3-matplotlib")
    output = tmp_path / "similarity.png"
    result = subprocess.run(
        [sys.executable, str(EXAMPLES / "detect_and_plot.py"), str(SAMPLES / "samples"),
         "--gt", str(SAMPLES / "samples_GT_pairs.txt"), "-o", str(output)],
        capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert "84 images, 41 loops detected; precision 1.000, recall 0.932" in result.stdout
    assert "detecting loops" in result.stderr, "progress=True prints the CLI's progress"
    pixels = image.imread(output)
    height, width = pixels.shape[:2]
    assert height >= 600 and width >= 600
    # A drawn matrix, not a blank page: many distinct colours.
    colours = {tuple(p) for p in (pixels[::4, ::4, :3] * 255).astype(int).reshape(-1, 3)}
    assert len(colours) > 200


def test_detect_and_plot_reports_errors_plainly(tmp_path):
    result = subprocess.run(
        [sys.executable, str(EXAMPLES / "detect_and_plot.py"), str(tmp_path / "missing"),
         "-o", str(tmp_path / "x.png")], capture_output=True, text=True, timeout=60)
    assert result.returncode == 1
    assert result.stderr.startswith("detect_and_plot.py: error: ") and "missing" in result.stderr
    assert not (tmp_path / "x.png").exists()
