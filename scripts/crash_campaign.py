#!/usr/bin/env python3
"""Crash and disk-full campaigns against binbow's database saves.

Runs `binbow db add` (incremental, then --compact) under strace, which stops
the process with SIGKILL at the Nth call of each file-changing system call
(the kill campaign), or makes every call of it from the Nth on fail with
ENOSPC (the disk-full campaign), for every N the command makes; then kills it
at random times within its run. After each
trial the database must load (`binbow info`, which loads it whole), hold
either the entries it had before or those with the new image, and hold the
new image whenever the command said it was added (exit 0): nothing damaged,
nothing unloadable, no acknowledged change lost. A later `db add` must then
succeed, so that what the dead writer left never blocks the next one.

Usage: crash_campaign.py BINBOW VOCABULARY IMAGE_DIR [--max-trials N]
                         [--random-kills N] [--seed S]
  (Debian: strace). Prints one line per campaign and a summary line
  "N passed, N failed"; exits 1 on any failure.
"""
import argparse
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time

# What can change a file: writes, syncs, renames, links, removals, sizes, modes.
SYSCALLS = ["write", "pwrite64", "ftruncate", "fsync", "fdatasync", "rename", "renameat2",
            "link", "unlink", "unlinkat", "fchmod"]


def run(command, **kwargs):
    return subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, **kwargs)


def entries(binbow, database):
    """The database's entries as a load gives them, or None if it does not load."""
    result = run([binbow, "info", database])
    if result.returncode != 0:
        return None
    match = re.search(r"^entries: (\d+)$", result.stdout, re.M)
    return int(match.group(1)) if match else None


def call_counts(binbow, command, work):
    """How often the command calls each system call of SYSCALLS."""
    log = os.path.join(work, "strace.log")
    result = run(["strace", "-f", "-qq", "-c", "-o", log, "-e", "trace=" + ",".join(SYSCALLS)]
                 + command)
    if result.returncode != 0:
        raise SystemExit("crash_campaign: the command fails without faults:\n" + result.stdout)
    counts = {}
    with open(log, encoding="utf-8") as file:
        for line in file:
            fields = line.split()
            if len(fields) >= 5 and fields[-1] in SYSCALLS and fields[3].isdigit():
                counts[fields[-1]] = int(fields[3])
    return counts


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("binbow")
    parser.add_argument("vocabulary")
    parser.add_argument("images")
    parser.add_argument("--max-trials", type=int, default=0,
                        help="at most this many trials per campaign, drawn at random (0: all)")
    parser.add_argument("--random-kills", type=int, default=50,
                        help="kills at random times during each command (default 50)")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    if shutil.which("strace") is None:
        raise SystemExit("crash_campaign: strace is needed (Debian: strace)")
    images = sorted(os.path.join(args.images, name) for name in os.listdir(args.images)
                    if name.endswith(".jpg"))
    if len(images) < 4:
        raise SystemExit(f"crash_campaign: {args.images} holds fewer than 4 .jpg images")
    rng = random.Random(args.seed)
    work = tempfile.mkdtemp(prefix="binbow-crash-")
    passed = failed = 0
    try:
        pristine = os.path.join(work, "pristine.bbdb")
        result = run([args.binbow, "db", "build", "--vocab", args.vocabulary, "-o", pristine,
                      images[0], images[1]])
        if result.returncode != 0:
            raise SystemExit("crash_campaign: db build failed:\n" + result.stdout)
        # A journal already there, so that appends, seals and compactions all run.
        run([args.binbow, "db", "add", pristine, images[2]])
        before = entries(args.binbow, pristine)
        database = os.path.join(work, "db.bbdb")

        def fresh():
            for name in os.listdir(work):
                if name.startswith("db.bbdb"):
                    os.unlink(os.path.join(work, name))
            shutil.copy(pristine, database)
            shutil.copy(pristine + ".journal", database + ".journal")

        for compact in (False, True):
            add = [args.binbow, "db", "add", database, images[3]] + (["--compact"] if compact
                                                                     else [])
            fresh()
            counts = call_counts(args.binbow, add, work)
            fresh()
            started = time.monotonic()
            run(add)
            duration = time.monotonic() - started
            for fault in ("signal=KILL", "error=ENOSPC", "random"):
                if fault == "random":
                    trials = [("SIGKILL after", rng.uniform(0, duration))
                              for _ in range(args.random_kills)]
                else:
                    trials = [(name, n) for name, count in sorted(counts.items())
                              for n in range(1, count + 1)]
                    if args.max_trials and len(trials) > args.max_trials:
                        trials = rng.sample(trials, args.max_trials)
                failures = []
                for name, n in trials:
                    fresh()
                    if fault == "random":
                        process = subprocess.Popen(add, stdout=subprocess.DEVNULL,
                                                   stderr=subprocess.DEVNULL)
                        time.sleep(n)
                        process.kill()
                        result = subprocess.CompletedProcess(add, process.wait())
                        n = f"{n:.3f} s"
                    else:
                        when = f"{n}+" if fault.startswith("error") else str(n)
                        result = run(["strace", "-f", "-qq", "-o", "/dev/null", "-e",
                                      f"inject={name}:{fault}:when={when}"] + add)
                    found = entries(args.binbow, database)
                    problem = None
                    if found is None:
                        problem = "does not load"
                    elif found not in (before, before + 1):
                        problem = f"{found} entries, expected {before} or {before + 1}"
                    elif result.returncode == 0 and found != before + 1:
                        problem = "an acknowledged add was lost"
                    elif run(add).returncode != 0:
                        problem = "the next db add fails"
                    if problem:
                        failures.append(f"{name} #{n}: {problem}")
                kind = "SIGKILL at random times" if fault == "random" else fault
                label = f"{'db add --compact' if compact else 'db add'}, {kind}"
                print(f"{label}: {len(trials) - len(failures)} of {len(trials)} trials intact")
                for failure in failures[:20]:
                    print("  " + failure)
                passed += len(trials) - len(failures)
                failed += len(failures)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
