"""Builds the binbow Python package.

The extension is built by the project's CMake (Release, the library's runtime
CPU dispatch: per-file -mpopcnt / -mavx512* kernels chosen at run time), so it
is the same code as the C++ library. The package is laid out as an installed
prefix: the `binbow` CLI, built by the same CMake run, is binbow/bin/binbow
and the bundled data (default vocabularies, the demo's sample sequence, each
with its license notice) binbow/share/binbow, where the CLI looks for it
(<exe>/../share/binbow); the `binbow` console script and `python -m binbow`
exec that CLI (binbow/_cli.py). The image/video module (OpenCV's imgcodecs and
videoio, loaded on first use) is binbow/lib/binbow/binbow_media.so. The
version is the file VERSION's, as CMake's project(). More CMake
arguments come from the CMAKE_ARGS environment variable (as scikit-build and
conda-build read it), e.g. CMAKE_ARGS="-DBINBOW_WARNINGS_AS_ERRORS=ON".

The build happens outside the source tree (build_base()), and the C++ build,
about 15 minutes on 2 cores, reports its progress: CMake's and Ninja's output
goes to setup.py's output (shown by pip install -v), and a progress line to
the terminal, which pip without -v leaves to its own spinner otherwise.
"""
import os
import hashlib
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent


def project_version():
    version = (ROOT / "VERSION").read_text(encoding="utf-8").strip()
    if not re.fullmatch(r"[0-9]+\.[0-9]+\.[0-9]+", version):
        sys.exit(f"setup.py: VERSION must hold major.minor.patch, not {version!r}")
    return version


def build_base(environ=os.environ, source=ROOT):
    """setuptools' build folder (and the CMake build in it), outside the source tree.

    pip builds in the source tree itself: a folder in it would mix with the
    developers' CMake build/ and leave the wheel's build behind in the
    checkout. $BINBOW_PIP_BUILD_DIR chooses the folder; by default it is one
    per user and checkout in the temporary folder, so that installing again
    reuses the CMake build.
    """
    chosen = environ.get("BINBOW_PIP_BUILD_DIR")
    if chosen:
        return Path(chosen).resolve()
    checkout = hashlib.sha256(str(source).encode()).hexdigest()[:12]
    return Path(tempfile.gettempdir()) / f"binbow-pip-build-{os.getuid()}-{checkout}"


# Ninja's "[12/136] Building ..." and Make's "[ 45%] Building ...".
NINJA_STEP = re.compile(r"^\[(\d+)/(\d+)\]")
MAKE_STEP = re.compile(r"^\[\s*(\d+)%\]")


def build_progress(line):
    """The percentage done that a line of the build's output shows, or None."""
    match = NINJA_STEP.match(line)
    if match:
        done, total = int(match.group(1)), int(match.group(2))
        return 100 * done // total if total else None
    match = MAKE_STEP.match(line)
    return int(match.group(1)) if match else None


def open_terminal():
    """The terminal, when pip hides this process's output from it; else None."""
    if sys.stdout.isatty():
        return None
    try:
        return open("/dev/tty", "w", encoding="utf-8")
    except OSError:
        return None


def run_reporting(command, what, output=sys.stdout, terminal=None, step=5):
    """Runs `command`, its output line by line to `output` and its progress to `terminal`."""
    print(f"setup.py: {what}: {shlex.join(command)}", file=output, flush=True)
    started = time.monotonic()
    reported = None
    with subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          errors="replace") as process:
        for line in process.stdout:
            output.write(line)
            output.flush()
            percent = build_progress(line)
            # Every `step` percent: some twenty lines over the whole build.
            if terminal is not None and percent is not None and (
                    reported is None or percent >= reported + step or
                    (percent == 100 and reported != 100)):
                minutes, seconds = divmod(int(time.monotonic() - started), 60)
                terminal.write(f"binbow: {what}: {percent}% ({minutes}:{seconds:02d})\n")
                terminal.flush()
                reported = percent
    if process.returncode != 0:
        sys.exit(f"setup.py: {what} failed (exit status {process.returncode}): "
                 f"{shlex.join(command)}")


class BuildWithCMake(build_ext):
    """Configures the project in the build folder and builds the module and the CLI."""

    def build_extension(self, ext):
        build_dir = Path(self.build_temp).resolve() / "cmake"
        configure = [
            "cmake", "-S", str(ROOT), "-B", str(build_dir),
            "-DCMAKE_BUILD_TYPE=Release",
            "-DBINBOW_BUILD_TESTS=OFF", "-DBINBOW_BUILD_BENCH=OFF", "-DBINBOW_BUILD_PYTHON=ON",
            # Static binbow libraries: the module and the CLI need no library of the build folder.
            "-DBUILD_SHARED_LIBS=OFF",
            f"-DPython3_EXECUTABLE={sys.executable}",
        ]
        if shutil.which("ninja"):
            configure += ["-G", "Ninja"]
        if shutil.which("ccache"):
            configure.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
        configure += shlex.split(os.environ.get("CMAKE_ARGS", ""))
        jobs = self.parallel or os.cpu_count() or 1
        terminal = open_terminal()
        if terminal is not None:
            terminal.write(f"binbow: building the C++ module and CLI in {build_dir} "
                           "(about 15 minutes on 2 cores; pip install -v shows every step)\n")
        try:
            run_reporting(configure, "configuring with CMake", terminal=terminal)
            run_reporting(["cmake", "--build", str(build_dir), "--target", "binbow_python",
                           "binbow", "-j", str(jobs)], "building with CMake", terminal=terminal)
        finally:
            if terminal is not None:
                terminal.close()
        built = sorted((build_dir / "python" / "binbow").glob("_binbow*.so"))
        if not built:
            sys.exit(f"setup.py: CMake built no _binbow module in {build_dir / 'python' / 'binbow'}")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)
        cli = build_dir / "bin" / "binbow"
        if not cli.is_file():
            sys.exit(f"setup.py: CMake built no binbow CLI at {cli}")
        packaged_cli = target.parent / "bin" / "binbow"
        packaged_cli.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(cli, packaged_cli)
        packaged_cli.chmod(0o755)
        # The image/video module, loaded on first use from <package>/lib/binbow.
        media = build_dir / "python" / "binbow" / "lib" / "binbow" / "binbow_media.so"
        if not media.is_file():
            sys.exit(f"setup.py: CMake built no image/video module at {media}")
        packaged_media = target.parent / "lib" / "binbow" / "binbow_media.so"
        packaged_media.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(media, packaged_media)
        # The CLI's commands that need OpenCV, a module beside it, loaded by
        # bin/binbow from <package>/lib/binbow as from an installed prefix.
        commands = build_dir / "lib" / "binbow" / "binbow_cli_vision.so"
        if not commands.is_file():
            sys.exit(f"setup.py: CMake built no CLI commands module at {commands}")
        shutil.copyfile(commands, packaged_media.parent / "binbow_cli_vision.so")


class BuildWithData(build_py):
    """Adds the bundled data as the CLI expects it and tells the package where it is."""

    def run(self):
        super().run()
        package = Path(self.build_lib) / "binbow"
        data = package / "share" / "binbow"
        if data.exists():
            shutil.rmtree(data)
        # The vocabularies with their provenance, the sample with its LICENSE.
        vocab = data / "vocab"
        vocab.mkdir(parents=True)
        for source in sorted((ROOT / "data" / "vocab").glob("*.bbw")):
            shutil.copyfile(source, vocab / source.name)
        shutil.copyfile(ROOT / "data" / "vocab" / "PROVENANCE.md", vocab / "PROVENANCE.md")
        shutil.copytree(ROOT / "data" / "samples", data / "samples")
        (package / "_data_location.py").write_text(
            "# Written by setup.py: the bundled data folder and the CLI, relative to this package.\n"
            'DATA_DIRECTORY = "share/binbow"\n'
            'CLI_EXECUTABLE = "bin/binbow"\n',
            encoding="utf-8",
        )


if __name__ == "__main__":
    base = build_base()
    base.mkdir(parents=True, exist_ok=True)
    setup(
        version=project_version(),
        options={"build": {"build_base": str(base)}, "egg_info": {"egg_base": str(base)}},
        ext_modules=[Extension("binbow._binbow", sources=[])],
        cmdclass={"build_ext": BuildWithCMake, "build_py": BuildWithData},
    )
