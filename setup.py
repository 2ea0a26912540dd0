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
version is the one of CMakeLists.txt's project(VERSION). More CMake
arguments come from the CMAKE_ARGS environment variable (as scikit-build and
conda-build read it), e.g. CMAKE_ARGS="-DBINBOW_WARNINGS_AS_ERRORS=ON".
"""
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
# setuptools' own folders (and the CMake build in it), apart from the
# developers' CMake build folder and out of the source tree's python/.
BUILD_BASE = "build/python-package"


def project_version():
    text = (ROOT / "CMakeLists.txt").read_text(encoding="utf-8")
    match = re.search(r"project\(\s*binbow\s+VERSION\s+([0-9][0-9.]*)", text)
    if not match:
        sys.exit("setup.py: no project(binbow VERSION x.y.z) in CMakeLists.txt")
    return match.group(1)


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
        subprocess.run(configure, check=True)
        subprocess.run(
            ["cmake", "--build", str(build_dir), "--target", "binbow_python", "binbow",
             "-j", str(jobs)],
            check=True,
        )
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


Path(BUILD_BASE).mkdir(parents=True, exist_ok=True)
setup(
    version=project_version(),
    options={"build": {"build_base": BUILD_BASE}, "egg_info": {"egg_base": BUILD_BASE}},
    ext_modules=[Extension("binbow._binbow", sources=[])],
    cmdclass={"build_ext": BuildWithCMake, "build_py": BuildWithData},
)
