"""The package installs: pip install from the source tree, and cmake --install.

Each installed copy is imported by a clean interpreter (-I: no PYTHONPATH, no
user site, not this source tree) from another folder, and must give the
project's version and the bundled default vocabularies.

pip is needed (Debian's python3-pip, installed by scripts/install-deps.sh);
where it cannot be installed, BINBOW_SKIP_PIP_TEST=1 skips the pip test alone.
"""
import os
import re
import subprocess
import sys

import pytest

from conftest import SOURCE_DIR, require_env

pytestmark = pytest.mark.packaging

CHECK = """
import sys, numpy as np, binbow
assert binbow.__version__ == sys.argv[1], (binbow.__version__, sys.argv[1])
assert binbow.__file__.startswith(sys.argv[2]), binbow.__file__
for name in ("orb", "brief"):
    vocabulary = binbow.Vocabulary.default(name)
    assert vocabulary.descriptor == name and vocabulary.word_count > 1000, vocabulary
db = binbow.Database(vocabulary)
db.add(None, label="empty")
db.add(np.zeros((5, 32), np.uint8))
assert len(db) == 2 and db.label(0) == "empty"
# The whole pipeline, with the vocabulary installed with the package.
results = binbow.detect_loops(sys.argv[3])
assert len(results) == 84 and sum(r.detection for r in results) == 41, results
print("imported", binbow.__file__, binbow.__version__)
"""


def project_version():
    text = (SOURCE_DIR / "CMakeLists.txt").read_text(encoding="utf-8")
    return re.search(r"project\(\s*binbow\s+VERSION\s+([0-9.]+)", text).group(1)


def import_installed(site_dir, cwd, extra_env=None):
    """Imports binbow from `site_dir` alone, in a fresh process started in `cwd`."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "BINBOW_"))}
    env.update(extra_env or {})
    code = f"import sys; sys.path.insert(0, {str(site_dir)!r})\n" + CHECK
    result = subprocess.run(
        [sys.executable, "-I", "-c", code, project_version(), str(site_dir),
         str(SOURCE_DIR / "data" / "samples" / "rtabmap" / "samples")],
        cwd=cwd, env=env, capture_output=True, text=True,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "imported" in result.stdout


def test_pip_install_from_the_source_tree(tmp_path):
    pip = subprocess.run([sys.executable, "-m", "pip", "--version"], capture_output=True)
    if pip.returncode != 0:
        if os.environ.get("BINBOW_SKIP_PIP_TEST") == "1":
            pytest.skip("pip is missing and BINBOW_SKIP_PIP_TEST=1")
        pytest.fail("pip is missing: install Debian's python3-pip (scripts/install-deps.sh), "
                    "or set BINBOW_SKIP_PIP_TEST=1 to skip this test")
    target = tmp_path / "site"
    result = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-build-isolation", "--no-deps",
         "--no-index", "--no-cache-dir", "--target", str(target), str(SOURCE_DIR)],
        cwd=SOURCE_DIR, capture_output=True, text=True,
    )
    assert result.returncode == 0, result.stdout[-4000:] + result.stderr[-4000:]
    package = target / "binbow"
    for name in ("__init__.py", "__init__.pyi", "py.typed", "data/vocab/orb_default.bbw",
                 "data/vocab/brief_default.bbw"):
        assert (package / name).is_file(), f"pip installed no binbow/{name}"
    assert list(package.glob("_binbow*.so")), "pip installed no extension"
    import_installed(target, tmp_path)


def test_cmake_install_puts_the_package_in_the_prefix(tmp_path):
    build_dir = require_env("BINBOW_BUILD_DIR")
    cmake = os.environ.get("CMAKE_COMMAND", "cmake")
    prefix = tmp_path / "prefix"
    result = subprocess.run([cmake, "--install", build_dir, "--prefix", str(prefix)],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    version = f"python{sys.version_info.major}.{sys.version_info.minor}"
    site_dir = prefix / "lib" / version / "site-packages"
    assert (site_dir / "binbow" / "py.typed").is_file(), f"no package in {site_dir}"
    # The vocabularies come from <prefix>/share/binbow: moving the prefix keeps them found.
    moved = tmp_path / "moved"
    prefix.rename(moved)
    import_installed(moved / "lib" / version / "site-packages", tmp_path)
