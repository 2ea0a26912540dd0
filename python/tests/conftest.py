"""Shared helpers of the binbow Python tests (run with python3 -m pytest).

The package under test is the one on PYTHONPATH: ctest points it at the build
tree's build/python.
"""
import csv
import importlib
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

SOURCE_DIR = Path(__file__).resolve().parents[2]

try:
    import binbow
except ImportError as error:  # pragma: no cover - a setup problem, said plainly
    raise ImportError(
        f"cannot import binbow ({error}): build it (cmake --build build) and run the tests with "
        "PYTHONPATH=build/python, or through ctest"
    ) from error


def clustered(rng, rows, centers=50, noise=0.08, code_size=32):
    """Random descriptors around `centers` random centres, like real features."""
    base = rng.integers(0, 256, size=(centers, code_size), dtype=np.uint8)
    picked = base[rng.integers(0, centers, size=rows)]
    bits = np.unpackbits(picked, axis=1)
    flips = rng.random(bits.shape) < noise
    return np.packbits(bits ^ flips, axis=1)


@pytest.fixture(scope="session")
def images():
    rng = np.random.default_rng(1)
    return [clustered(rng, 300) for _ in range(12)]


@pytest.fixture(scope="session")
def vocabulary(images):
    return binbow.Vocabulary.build(images, branching=5, levels=3, seed=3)


@pytest.fixture()
def database(vocabulary, images):
    db = binbow.Database(vocabulary)
    for i, image in enumerate(images):
        db.add(image, label=f"image {i}")
    return db


def require_env(name):
    """The value of an environment variable ctest sets; a clear failure without it."""
    value = os.environ.get(name)
    if not value:
        pytest.fail(f"${name} is not set: run this test through ctest (python.packaging)")
    return value


SAMPLES = SOURCE_DIR / "data" / "samples" / "rtabmap"


def sample_frames():
    """The bundled sample's 84 frames in the CLI's natural order (2.jpg before 10.jpg)."""
    frames = sorted((SAMPLES / "samples").glob("*.jpg"), key=lambda p: int(p.stem))
    if len(frames) != 84:
        pytest.fail(f"the bundled sample {SAMPLES / 'samples'} should have 84 frames, "
                    f"found {len(frames)}")
    return frames


def cli():
    """The binbow command of the build tree under test."""
    binary = Path(require_env("BINBOW_BUILD_DIR")) / "bin" / "binbow"
    if not binary.is_file():
        pytest.fail(f"{binary} does not exist: build the binbow target")
    return binary


def run_cli(*arguments, cwd=SOURCE_DIR):
    result = subprocess.run([str(cli()), *map(str, arguments)], cwd=cwd, capture_output=True,
                            text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    return result


@pytest.fixture(scope="session")
def cli_loops(tmp_path_factory):
    """loops.csv of `binbow detect-loops` on the bundled sample, as (path, rows)."""
    path = tmp_path_factory.mktemp("cli") / "loops.csv"
    run_cli("detect-loops", "-o", path, SAMPLES / "samples")
    with open(path, newline="", encoding="utf-8") as file:
        rows = list(csv.DictReader(file))
    assert rows, "the CLI found no loop on the bundled sample"
    return path, rows


def require_module(name, package):
    """Imports `name`; a clear failure (not a skip) when its Debian package is missing."""
    try:
        return importlib.import_module(name)
    except ImportError as error:
        pytest.fail(f"cannot import {name} ({error}): install Debian's {package} "
                    "(scripts/install-deps.sh)")
