#!/usr/bin/env python3
"""Checks the project's license files; exits 1 naming each problem.

- LICENSE is the BSD 3-Clause license of "the binbow authors".
- Every file under data/ and fuzz/corpus/ matches a pattern of a `Files:` line of
  THIRD_PARTY.md, so nothing is shipped without its origin and license written down.
- Every pattern there matches a file, so the list does not outlive the files.
- Every notice file named on a `Notice:` line exists.

    scripts/check_third_party.py [SOURCE_DIR]   (default: this script's repository)
"""
import re
import sys
from pathlib import Path

# Folders whose every file must have an entry: the data binbow ships and the
# fuzz corpora, the two places where files of other projects could land.
COVERED_FOLDERS = ("data", "fuzz/corpus")

BSD_3_CLAUSE_PHRASES = (
    "BSD 3-Clause License",
    "Copyright (c) 2026, the binbow authors",
    "Redistributions of source code must retain the above copyright notice",
    "Redistributions in binary form must reproduce the above copyright notice",
    "Neither the name of the copyright holder nor the names of its",
    "contributors may be used to endorse or promote products derived from",
    'THIS SOFTWARE IS PROVIDED BY THE COPYRIGHT HOLDERS AND CONTRIBUTORS "AS IS"',
)


def check_license(root):
    path = root / "LICENSE"
    if not path.is_file():
        return [f"{path}: missing; binbow's license (BSD 3-Clause) belongs there"]
    text = " ".join(path.read_text(encoding="utf-8").split())
    return [f"{path}: not the BSD 3-Clause license of the binbow authors: no {phrase!r}"
            for phrase in BSD_3_CLAUSE_PHRASES if phrase not in text]


def backticked(line):
    return re.findall(r"`([^`]+)`", line)


def check_third_party(root):
    listing = root / "THIRD_PARTY.md"
    if not listing.is_file():
        return [f"{listing}: missing; it lists every third-party file and its license"]
    lines = listing.read_text(encoding="utf-8").splitlines()
    patterns = [p for line in lines if line.startswith("Files:") for p in backticked(line)]
    notices = [p for line in lines if line.lstrip("- ").startswith("Notice:")
               for p in backticked(line) if not p.startswith("<") and "/" in p]
    problems = []
    if not patterns:
        problems.append(f"{listing}: no `Files:` line")
    listed = set()
    for pattern in patterns:
        matched = {p for p in root.glob(pattern) if p.is_file()}
        if not matched:
            problems.append(f"THIRD_PARTY.md: `{pattern}` matches no file")
        listed |= matched
    files = sorted(p for folder in COVERED_FOLDERS for p in (root / folder).rglob("*")
                   if p.is_file())
    if not files:
        problems.append(f"{root}: no file under {' or '.join(COVERED_FOLDERS)}; wrong folder?")
    for path in files:
        if path not in listed:
            problems.append(f"{path.relative_to(root).as_posix()}: not listed in THIRD_PARTY.md: "
                            "add its origin and license")
    for notice in notices:
        if not (root / notice).is_file():
            problems.append(f"THIRD_PARTY.md: notice file `{notice}` does not exist")
    return problems


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parents[1])
    problems = check_license(root) + check_third_party(root)
    for problem in problems:
        print(f"check_third_party: {problem}", file=sys.stderr)
    if not problems:
        print(f"check_third_party: LICENSE and THIRD_PARTY.md cover {root}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
