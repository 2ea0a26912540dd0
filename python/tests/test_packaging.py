"""The package installs: pip install from the source tree, and cmake --install.

Those tests are marked `packaging` (ctest's python.packaging). The others run
with the module's tests: the Python metadata, and setup.py's own logic (its
build folder outside the source tree, the progress it reports), called
without a build.

Each installed copy is imported by a clean interpreter (-I: no PYTHONPATH, no
user site, not this source tree) from another folder, and must give the
project's version and the bundled default vocabularies. Its `binbow` command
(the console script, `python -m binbow`) must be the C++ CLI of the build
under test: same version, errors and exit statuses. Both installs carry
binbow's license and the third-party notices.

pip is needed (Debian's python3-pip, installed by scripts/install-deps.sh);
where it cannot be installed, BINBOW_SKIP_PIP_TEST=1 skips the pip test alone.
"""
import importlib.util
import io
import os
import signal
import subprocess
import sys
import tarfile
import tomllib

import pytest

from conftest import SOURCE_DIR, cli, require_env

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
assert len(results) == 84 and sum(r.detection for r in results) == 40, results
print("imported", binbow.__file__, binbow.__version__)
"""


def project_version():
    return (SOURCE_DIR / "VERSION").read_text(encoding="utf-8").strip()


def import_installed(site_dir, cwd, extra_env=None):
    """Imports binbow from `site_dir` alone, in a fresh process started in `cwd`."""
    env = clean_env(**(extra_env or {}))
    code = f"import sys; sys.path.insert(0, {str(site_dir)!r})\n" + CHECK
    result = subprocess.run(
        [sys.executable, "-I", "-c", code, project_version(), str(site_dir),
         str(SOURCE_DIR / "data" / "samples" / "rtabmap" / "samples")],
        cwd=cwd, env=env, capture_output=True, text=True,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "imported" in result.stdout


def clean_env(**extra):
    """The environment without the test's PYTHON* and BINBOW_* settings."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "BINBOW_"))}
    env.update(extra)
    return env


def run(command, env, cwd, stdout=subprocess.PIPE):
    return subprocess.run(command, env=env, cwd=cwd, stdout=stdout, stderr=subprocess.PIPE,
                          text=True, timeout=600)


def check_command_is_the_cli(command, env, cwd):
    """`command` (a list) behaves as the C++ build's binbow: output, errors, signals."""
    expected = run([str(cli()), "--version"], os.environ, cwd)
    assert expected.returncode == 0 and expected.stdout.startswith("binbow "), expected
    version = run([*command, "--version"], env, cwd)
    assert (version.returncode, version.stdout) == (0, expected.stdout), (command, version)
    assert version.stdout.strip() == f"binbow {project_version()}"

    unknown = run([*command, "no-such-command"], env, cwd)
    assert unknown.returncode == 1, (command, unknown)
    assert unknown.stderr.startswith("binbow: error:"), (command, unknown.stderr)

    # A closed pipe ends it by SIGPIPE, as the C++ command (Python ignores SIGPIPE).
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        piped = run([*command, "--version"], env, cwd, stdout=write_end)
        direct = run([str(cli()), "--version"], os.environ, cwd, stdout=write_end)
    finally:
        os.close(write_end)
    assert piped.returncode == direct.returncode == -signal.SIGPIPE, (piped, direct)


def check_info_of_bundled_vocabulary(command, vocabulary, env, cwd):
    info = run([*command, "info", str(vocabulary)], env, cwd)
    assert info.returncode == 0, (command, info)
    assert "kind: vocabulary" in info.stdout and "descriptor: orb" in info.stdout, info.stdout


def check_license_metadata(dist_info):
    metadata = (dist_info / "METADATA").read_text(encoding="utf-8")
    lines = metadata.splitlines()
    assert f"Version: {project_version()}" in lines, metadata[:2000]
    assert "License: BSD-3-Clause" in lines, metadata[:2000]
    assert "Classifier: License :: OSI Approved :: BSD License" in metadata, metadata[:2000]
    # Who makes it and where it lives, as pyproject.toml says.
    for start in ("Author-email: binbow maintainers", "Project-URL: Homepage, https://"):
        assert any(line.startswith(start) for line in lines), (start, metadata[:2000])
    for name in ("LICENSE", "THIRD_PARTY.md"):
        found = list(dist_info.rglob(name))
        assert found, f"no {name} in {dist_info}"
        assert found[0].read_bytes() == (SOURCE_DIR / name).read_bytes(), found[0]


@pytest.mark.packaging
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
    for name in ("__init__.py", "__init__.pyi", "py.typed", "__main__.py", "bin/binbow",
                 "lib/binbow/binbow_media.so", "lib/binbow/binbow_cli_vision.so",
                 "share/binbow/vocab/orb_default.bbw", "share/binbow/vocab/brief_default.bbw",
                 "share/binbow/vocab/PROVENANCE.md", "share/binbow/samples/rtabmap/LICENSE",
                 "share/binbow/samples/rtabmap/samples_GT.bmp"):
        assert (package / name).is_file(), f"pip installed no binbow/{name}"
    assert list(package.glob("_binbow*.so")), "pip installed no extension"
    dist_info = list(target.glob("binbow-*.dist-info"))
    assert len(dist_info) == 1, f"no binbow .dist-info in {target}"
    check_license_metadata(dist_info[0])
    import_installed(target, tmp_path)

    # The console script and python -m binbow, from another folder.
    env = clean_env(PYTHONPATH=str(target))
    vocabulary = package / "share" / "binbow" / "vocab" / "orb_default.bbw"
    for command in ([str(target / "bin" / "binbow")], [sys.executable, "-m", "binbow"]):
        check_command_is_the_cli(command, env, tmp_path)
        check_info_of_bundled_vocabulary(command, vocabulary, env, tmp_path)
    # The demo finds the sample and the vocabulary installed in the package.
    demo = run([str(target / "bin" / "binbow"), "demo", "--out", str(tmp_path / "demo")], env,
               tmp_path)
    assert demo.returncode == 0, demo.stdout[-2000:] + demo.stderr[-2000:]
    assert "precision: 1\n" in demo.stdout, demo.stdout
    assert f"vocabulary: {vocabulary.resolve()}" in demo.stdout, demo.stdout
    # Ctrl-C during the demo (its first line is printed before the work starts) ends it.
    interrupted = subprocess.Popen(
        [sys.executable, "-m", "binbow", "demo", "--out", str(tmp_path / "interrupted")],
        env=env, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    first_line = interrupted.stdout.readline()
    interrupted.send_signal(signal.SIGINT)
    rest, errors = interrupted.communicate(timeout=600)
    assert first_line.startswith("== binbow demo"), first_line + rest + errors
    assert interrupted.returncode == -signal.SIGINT, (interrupted.returncode, rest, errors)


@pytest.mark.packaging
def test_sdist_carries_the_sources_and_the_licenses(tmp_path):
    result = subprocess.run([sys.executable, "setup.py", "-q", "sdist", "-d", str(tmp_path)],
                            cwd=SOURCE_DIR, capture_output=True, text=True)
    assert result.returncode == 0, result.stdout[-4000:] + result.stderr[-4000:]
    archives = list(tmp_path.glob("binbow-*.tar.gz"))
    assert len(archives) == 1, list(tmp_path.iterdir())
    with tarfile.open(archives[0]) as archive:
        names = {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}
        pkg_info = archive.extractfile(f"binbow-{project_version()}/PKG-INFO").read().decode()
    for name in ("LICENSE", "THIRD_PARTY.md", "CMakeLists.txt", "setup.py", "pyproject.toml",
                 "src/CMakeLists.txt", "apps/binbow/main.cpp", "python/module.cpp",
                 "python/binbow/_cli.py", "data/samples/rtabmap/LICENSE",
                 "data/vocab/orb_default.bbw"):
        assert name in names, f"the sdist has no {name}"
    assert "License: BSD-3-Clause" in pkg_info.splitlines(), pkg_info[:2000]
    assert "Author-email: binbow maintainers" in pkg_info, pkg_info[:2000]
    assert "Project-URL: Homepage, https://" in pkg_info, pkg_info[:2000]
    assert "VERSION" in names, "the sdist has no VERSION, which setup.py and CMake read"


@pytest.mark.packaging
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
    for name in ("share/doc/binbow/LICENSE", "share/doc/binbow/THIRD_PARTY.md",
                 "share/binbow/samples/rtabmap/LICENSE", "share/binbow/vocab/PROVENANCE.md"):
        assert (prefix / name).is_file(), f"cmake --install put no {name} in the prefix"
    # The vocabularies come from <prefix>/share/binbow: moving the prefix keeps them found.
    moved = tmp_path / "moved"
    prefix.rename(moved)
    site_dir = moved / "lib" / version / "site-packages"
    import_installed(site_dir, tmp_path)
    # python -m binbow runs <prefix>/bin/binbow.
    env = clean_env(PYTHONPATH=str(site_dir))
    command = [sys.executable, "-m", "binbow"]
    check_command_is_the_cli(command, env, tmp_path)
    check_info_of_bundled_vocabulary(command, moved / "share/binbow/vocab/orb_default.bbw", env,
                                     tmp_path)


def load_setup_script():
    """setup.py as a module: its functions, without running setup()."""
    spec = importlib.util.spec_from_file_location("binbow_setup_script", SOURCE_DIR / "setup.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_python_metadata_says_who_what_and_where():
    project = tomllib.loads((SOURCE_DIR / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert project["dynamic"] == ["version"], "the version is VERSION's, read by setup.py"
    assert load_setup_script().project_version() == project_version()
    assert project["license"] == {"text": "BSD-3-Clause"}
    for field in ("authors", "maintainers"):
        (person,) = project[field]
        assert person["name"] and "@" in person["email"], person
        assert not person["email"].endswith((".invalid", ".example")), person
    for name in ("Homepage", "Documentation", "Changelog", "Issues"):
        assert project["urls"][name].startswith("https://"), project["urls"]
    classifiers = project["classifiers"]
    for expected in ("Development Status :: ", "License :: OSI Approved :: BSD License",
                     "Operating System :: POSIX :: Linux", "Programming Language :: C++",
                     "Programming Language :: Python :: 3", "Topic :: Scientific/Engineering"):
        assert any(c.startswith(expected) for c in classifiers), (expected, classifiers)


def test_pip_builds_outside_the_source_tree(tmp_path):
    setup_script = load_setup_script()
    default = setup_script.build_base({}, SOURCE_DIR)
    assert default.is_absolute() and SOURCE_DIR not in default.parents, default
    # One folder per checkout, so that two checkouts do not share a CMake build.
    assert setup_script.build_base({}, tmp_path / "other checkout") != default
    chosen = tmp_path / "chosen"
    assert setup_script.build_base({"BINBOW_PIP_BUILD_DIR": str(chosen)}, SOURCE_DIR) == chosen


def test_build_progress_reads_ninja_and_make():
    progress = load_setup_script().build_progress
    assert progress("[34/136] Building CXX object src/core/a.cpp.o\n") == 25
    assert progress("[136/136] Linking CXX executable bin/binbow\n") == 100
    assert progress("[ 45%] Building CXX object src/core/a.cpp.o\n") == 45
    assert progress("-- Configuring done\n") is None


def test_the_build_output_is_streamed_and_its_progress_reported():
    setup_script = load_setup_script()
    steps = [f"[{step}/20] Building CXX object {step}.o" for step in range(1, 21)]
    program = ("import sys\nfor line in sys.argv[1:]: print(line, flush=True)\n"
               "print('note', file=sys.stderr)")
    output, terminal = io.StringIO(), io.StringIO()
    setup_script.run_reporting([sys.executable, "-c", program, *steps], "building", output=output,
                               terminal=terminal)
    # Every line of the build, its errors included, in setup.py's output (pip install -v).
    for line in steps + ["note"]:
        assert line + "\n" in output.getvalue(), output.getvalue()
    # The terminal gets one line every 5 percent, and the end.
    reported = terminal.getvalue().splitlines()
    assert [line.split(": ")[2].split("%")[0] for line in reported] == [
        str(percent) for percent in range(5, 101, 5)], reported
    assert all(line.startswith("binbow: building: ") for line in reported), reported

    with pytest.raises(SystemExit, match="building failed \\(exit status 3\\)"):
        setup_script.run_reporting([sys.executable, "-c", "raise SystemExit(3)"], "building",
                                   output=io.StringIO())
