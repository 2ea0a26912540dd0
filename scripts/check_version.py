#!/usr/bin/env python3
"""Checks that every place holding binbow's version agrees with VERSION.

VERSION (major.minor.patch) is the one place the version is written: CMake's
project() and setup.py read it. The places that cannot read a file hold a copy,
checked here: package.xml (colcon, rosdep; its maintainer is also
pyproject.toml's authors and maintainers), the consumer projects of the package
test and the README (find_package(binbow major.minor), the shared libraries'
soname). Given a build, also what the build made of it: CMake's project
version, `binbow --version`, the Python module's __version__, and the Version:
of the generated pkg-config files. setup.py's version is asked of setup.py
itself, and pyproject.toml must leave the version to it.

With --release, also what a release needs (docs/releasing.md): a dated
CHANGELOG.md section for VERSION, the newest one.

Standard library only. Exit status 1 names every disagreement.

Usage: check_version.py SOURCE_DIR [--cmake-version V] [--cli BINBOW]
       [--python-path DIR] [--pc FILE ...] [--release]
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ElementTree
from pathlib import Path

VERSION_PATTERN = re.compile(r"[0-9]+\.[0-9]+\.[0-9]+")
# "## 0.1.0 — 2026-11-23": a released section of CHANGELOG.md.
RELEASE_HEADING = re.compile(r"^## ([0-9]+\.[0-9]+\.[0-9]+) — ([0-9]{4}-[0-9]{2}-[0-9]{2})$",
                             re.MULTILINE)


def read_version(source):
    path = source / "VERSION"
    if not path.is_file():
        raise SystemExit(f"check_version: no {path}")
    text = path.read_text(encoding="utf-8")
    version = text.strip()
    if not VERSION_PATTERN.fullmatch(version) or text != version + "\n":
        raise SystemExit(f"check_version: {path} must hold one line major.minor.patch, "
                         f"not {text!r}")
    return version


def as_tuple(version):
    return tuple(int(part) for part in version.split("."))


class Checker:
    def __init__(self, version):
        self.version = version
        self.minor = ".".join(version.split(".")[:2])
        self.errors = []
        self.checked = []

    def expect(self, place, found, expected):
        self.checked.append(place)
        if found != expected:
            self.errors.append(f"{place}: {found!r}, VERSION says {expected!r}")

    def fail(self, place, message):
        self.checked.append(place)
        self.errors.append(f"{place}: {message}")


def check_sources(source, check):
    package = ElementTree.parse(source / "package.xml").getroot()
    check.expect("package.xml <version>", package.findtext("version"), check.version)

    # The maintainers, as the Python metadata names them too.
    pyproject = (source / "pyproject.toml").read_text(encoding="utf-8")
    maintainer = package.find("maintainer")
    declared = (f'{{name = "{maintainer.text}", email = "{maintainer.get("email")}"}}'
                if maintainer is not None else None)
    for field in ("authors", "maintainers"):
        match = re.search(rf"^{field} = \[(.*)\]$", pyproject, re.MULTILINE)
        check.expect(f"pyproject.toml {field}", match.group(1) if match else None, declared)

    # pyproject.toml leaves the version to setup.py, which reads VERSION.
    if not re.search(r'^dynamic = \[[^]]*"version"', pyproject, re.MULTILINE):
        check.fail("pyproject.toml",
                   'the version must be dynamic = ["version"] (setup.py reads VERSION)')
    if re.search(r"^version\s*=", pyproject, re.MULTILINE):
        check.fail("pyproject.toml", "has a version of its own")
    # setup.py makes its build folder (BINBOW_PIP_BUILD_DIR): a scratch one here.
    with tempfile.TemporaryDirectory() as build:
        setup = subprocess.run([sys.executable, "setup.py", "--version"], cwd=source,
                               env=dict(os.environ, BINBOW_PIP_BUILD_DIR=build),
                               capture_output=True, text=True)
    lines = setup.stdout.strip().splitlines()
    check.expect("setup.py --version", lines[-1] if setup.returncode == 0 and lines else
                 f"failed ({setup.returncode}): {setup.stderr.strip()}", check.version)

    # What users pin: find_package(binbow major.minor) in the consumers, which
    # the package's SameMinorVersion compatibility must accept.
    consumers = sorted((source / "tests" / "package").glob("*/CMakeLists.txt"))
    pins = 0
    for consumer in consumers:
        text = consumer.read_text(encoding="utf-8")
        for pin in re.findall(r"find_package\(binbow ([0-9][0-9.]*)", text):
            pins += 1
            place = f"{consumer.relative_to(source)} find_package(binbow {pin})"
            check.expect(place, pin, check.minor)
    if not pins:
        check.fail("tests/package/*/CMakeLists.txt", "no find_package(binbow major.minor) found")

    readme = (source / "README.md").read_text(encoding="utf-8")
    for pin in re.findall(r"find_package\(binbow ([0-9][0-9.]*)", readme):
        check.expect(f"README.md find_package(binbow {pin})", pin, check.minor)
    sonames = re.findall(r"libbinbow_core\.so\.([0-9.]*[0-9])", readme)
    if not sonames:
        check.fail("README.md", "no libbinbow_core.so.<major.minor> found")
    for soname in sonames:
        check.expect("README.md libbinbow_core.so.<version>", soname, check.minor)

    # No release above VERSION: it was bumped when the newest section was cut.
    changelog = (source / "CHANGELOG.md").read_text(encoding="utf-8")
    released = RELEASE_HEADING.findall(changelog)
    if not released:
        check.fail("CHANGELOG.md", "no released section (## x.y.z — YYYY-MM-DD)")
    elif as_tuple(released[0][0]) > as_tuple(check.version):
        check.fail("CHANGELOG.md", f"its newest release {released[0][0]} is above VERSION")
    else:
        check.checked.append("CHANGELOG.md newest release not above VERSION")


def check_release(source, check):
    changelog = (source / "CHANGELOG.md").read_text(encoding="utf-8")
    released = RELEASE_HEADING.findall(changelog)
    check.expect("CHANGELOG.md newest dated section", released[0][0] if released else None,
                 check.version)


def check_build(args, check):
    if args.cmake_version is not None:
        check.expect("CMake project(VERSION)", args.cmake_version, check.version)
    if args.cli is not None:
        result = subprocess.run([args.cli, "--version"], capture_output=True, text=True)
        check.expect("binbow --version", result.stdout.strip(), f"binbow {check.version}")
    if args.python_path is not None:
        result = subprocess.run(
            [sys.executable, "-c", "import binbow; print(binbow.__version__)"],
            env={"PYTHONPATH": args.python_path, "PATH": "/usr/bin:/bin"},
            capture_output=True, text=True)
        check.expect("binbow.__version__", result.stdout.strip() if result.returncode == 0
                     else f"import failed: {result.stderr.strip()[-500:]}", check.version)
    for pc in args.pc:
        versions = re.findall(r"^Version:\s*(.*?)\s*$", Path(pc).read_text(encoding="utf-8"),
                              re.MULTILINE)
        check.expect(f"{Path(pc).name} Version:", versions, [check.version])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source", type=Path)
    parser.add_argument("--cmake-version")
    parser.add_argument("--cli")
    parser.add_argument("--python-path")
    parser.add_argument("--pc", nargs="*", default=[])
    parser.add_argument("--release", action="store_true")
    args = parser.parse_args()

    check = Checker(read_version(args.source))
    check_sources(args.source, check)
    if args.release:
        check_release(args.source, check)
    check_build(args, check)
    for place in check.checked:
        print(f"checked: {place}")
    if check.errors:
        for error in check.errors:
            print(f"check_version: error: {error}", file=sys.stderr)
        return 1
    print(f"check_version: {len(check.checked)} places agree on {check.version}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
