#!/usr/bin/env python3
"""scripts/check_version.py passes the source tree's files, and fails, naming
the place, on each copy of the version made to disagree; with --release it
fails until CHANGELOG.md has VERSION's dated section.

Usage: check_version_test.py <check_version.py> <source dir>
"""
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

# What check_version.py reads of the sources, and what setup.py --version needs.
FILES = ["VERSION", "package.xml", "pyproject.toml", "setup.py", "README.md", "CHANGELOG.md",
         "LICENSE", "THIRD_PARTY.md"]


def copy_sources(source, work):
    for name in FILES:
        shutil.copyfile(source / name, work / name)
    for consumer in (source / "tests" / "package").glob("*/CMakeLists.txt"):
        target = work / consumer.relative_to(source)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(consumer, target)
    (work / "python" / "binbow").mkdir(parents=True)


def check(checker, work, *extra):
    return subprocess.run([sys.executable, str(checker), str(work), *extra],
                          capture_output=True, text=True)


def edit(path, pattern, replacement):
    text = path.read_text(encoding="utf-8")
    changed, count = re.subn(pattern, replacement, text, count=1, flags=re.MULTILINE)
    if count != 1:
        raise SystemExit(f"check_version_test: FAIL: no {pattern!r} in {path} to change")
    path.write_text(changed, encoding="utf-8")


def main():
    checker, source = Path(sys.argv[1]), Path(sys.argv[2])
    version = (source / "VERSION").read_text(encoding="utf-8").strip()
    major, minor, patch = (int(part) for part in version.split("."))
    other = f"{major}.{minor + 1}.{patch}"
    failures = []

    # (what is changed, file, pattern, replacement, the error's place)
    mismatches = [
        ("package.xml", "package.xml", r"<version>[^<]*</version>", f"<version>{other}</version>",
         "package.xml <version>"),
        ("a consumer's pin", "tests/package/core/CMakeLists.txt", r"find_package\(binbow [0-9.]+",
         f"find_package(binbow {major}.{minor + 1}", "find_package(binbow"),
        ("the README's soname", "README.md", r"libbinbow_core\.so\.[0-9.]*[0-9]",
         f"libbinbow_core.so.{major}.{minor + 1}", "README.md libbinbow_core.so"),
        ("pyproject.toml's own version", "pyproject.toml", r'^dynamic = \[.*\].*$',
         f'version = "{other}"', "pyproject.toml"),
        ("VERSION below the newest release", "VERSION", r".*", "0.0.1", "newest release"),
    ]
    with tempfile.TemporaryDirectory() as temporary:
        work = Path(temporary) / "clean"
        work.mkdir()
        copy_sources(source, work)
        clean = check(checker, work)
        if clean.returncode != 0:
            failures.append(f"the source tree's files fail:\n{clean.stdout}{clean.stderr}")
        for what, name, pattern, replacement, place in mismatches:
            work = Path(temporary) / re.sub(r"\W+", "_", what)
            work.mkdir()
            copy_sources(source, work)
            edit(work / name, pattern, replacement)
            result = check(checker, work)
            if result.returncode != 1 or place not in result.stderr:
                failures.append(f"{what}: expected exit 1 naming {place!r}, got "
                                f"{result.returncode}:\n{result.stdout}{result.stderr}")
            else:
                print(f"found: {what}")

        # --release: VERSION's dated section must be the newest.
        work = Path(temporary) / "release"
        work.mkdir()
        copy_sources(source, work)
        changelog = work / "CHANGELOG.md"
        changelog.write_text(re.sub(rf"^## {re.escape(version)} — .*\n", "",
                                    changelog.read_text(encoding="utf-8"), flags=re.MULTILINE),
                             encoding="utf-8")
        result = check(checker, work, "--release")
        if result.returncode != 1 or "CHANGELOG.md newest dated section" not in result.stderr:
            failures.append(f"--release without a {version} section: expected exit 1, got "
                            f"{result.returncode}:\n{result.stdout}{result.stderr}")
        else:
            print("found: a release without its CHANGELOG section")
        edit(changelog, r"^## Unreleased\n", f"## Unreleased\n\n## {version} — 2026-12-01\n")
        result = check(checker, work, "--release")
        if result.returncode != 0:
            failures.append(f"--release with a {version} section fails:\n"
                            f"{result.stdout}{result.stderr}")

    if failures:
        for failure in failures:
            print(f"check_version_test: FAIL: {failure}", file=sys.stderr)
        return 1
    print("check_version_test: every disagreement found")
    return 0


if __name__ == "__main__":
    sys.exit(main())
