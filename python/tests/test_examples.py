"""python/examples run on the bundled sample."""
import importlib.util
import subprocess
import sys
from types import SimpleNamespace

import numpy as np

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
    assert "84 images, 40 loops detected; precision 1.000, recall 0.909" in result.stdout
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


def load_example(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_detect_and_plot_leaves_cells_without_an_earlier_image_blank():
    require_module("matplotlib", "python3-matplotlib")
    example = load_example("detect_and_plot")
    cells = 6
    scores = np.tril(np.full((cells, cells), 0.5, dtype=np.float32), k=-1)
    # One frame a cell: the diagonal pairs an image with itself, never scored
    # (0), and drawn it would be a black line through the colour map.
    shown = example.similarity_scores(SimpleNamespace(scores=scores, cells=cells, bin=1))
    assert np.isnan(np.diag(shown)).all()
    assert np.isnan(shown[np.triu_indices(cells, k=1)]).all()
    assert (shown[np.tril_indices(cells, k=-1)] == 0.5).all()
    # Binned cells: the diagonal holds pairs of frames within one bin.
    np.fill_diagonal(scores, 0.25)
    shown = example.similarity_scores(SimpleNamespace(scores=scores, cells=cells, bin=4))
    assert (np.diag(shown) == 0.25).all()
    assert np.isnan(shown[np.triu_indices(cells, k=1)]).all()
