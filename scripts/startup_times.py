#!/usr/bin/env python3
"""Start-up time of the binbow CLI beside a C++ hello-world linked with the
same standard library: the median wall and CPU (user + system) times of N
runs of each command, run in alternation, and the shared objects each loads
(LD_DEBUG=files). On a loaded machine the CPU time is the steadier figure.

    scripts/startup_times.py build/bin/binbow [N]
"""
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def timed_run(command):
    """Wall and CPU seconds of one run of `command`."""
    start = time.perf_counter()
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - start
    if status != 0:
        sys.exit(f"{command} failed ({status})")
    return wall, usage.ru_utime + usage.ru_stime


def loaded_objects(command):
    env = dict(os.environ, LD_DEBUG="files")
    result = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
    return {line.split("file=", 1)[1].split()[0] for line in result.stderr.splitlines()
            if "file=" in line and "generating link map" not in line}


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    cli = str(Path(sys.argv[1]).resolve())
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 50
    data = Path(__file__).resolve().parents[1] / "data"
    vocabulary = str(data / "vocab" / "orb_default.bbw")
    frames = sorted(str(p) for p in (data / "samples" / "rtabmap" / "samples").glob("*.jpg"))[:3]
    with tempfile.TemporaryDirectory() as scratch:
        hello = Path(scratch) / "hello"
        source = Path(scratch) / "hello.cpp"
        source.write_text('#include <iostream>\nint main() { std::cout << "hello\\n"; }\n')
        subprocess.run([os.environ.get("CXX", "c++"), "-O2", str(source), "-o", str(hello)],
                       check=True)
        database = str(Path(scratch) / "db.bbdb")
        subprocess.run([cli, "db", "build", "--vocab", vocabulary, "-o", database] + frames,
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        edited = str(Path(scratch) / "edited.bbdb")
        truth = Path(scratch) / "gt.txt"
        truth.write_text("# 0-based\n2 0\n")
        loops = Path(scratch) / "loops.csv"
        loops.write_text("query,match,score\n2,0,0.5\n")
        commands = (("hello-world (C++, libstdc++)", [str(hello)], None),
                    ("binbow --version", [cli, "--version"], None),
                    ("binbow info orb_default.bbw", [cli, "info", vocabulary], None),
                    ("binbow info --header-only DB.bbdb",
                     [cli, "info", "--header-only", database], None),
                    ("binbow info DB.bbdb", [cli, "info", database], None),
                    ("binbow db remove DB.bbdb 0", [cli, "db", "remove", edited, "0"],
                     lambda: shutil.copyfile(database, edited)),
                    ("binbow evaluate --gt pairs.txt loops.csv",
                     [cli, "evaluate", "--gt", str(truth), str(loops)], None))
        # Rounds alternate the commands, so that the load of a shared machine
        # weighs on each alike.
        times = {name: ([], []) for name, _, _ in commands}
        for _ in range(runs):
            for name, command, prepare in commands:
                if prepare:
                    prepare()
                wall, cpu = timed_run(command)
                times[name][0].append(wall)
                times[name][1].append(cpu)
        hello_cpu = statistics.median(times[commands[0][0]][1])
        for name, command, prepare in commands:
            if prepare:
                prepare()
            wall = statistics.median(times[name][0])
            cpu = statistics.median(times[name][1])
            print(f"{name}: wall {wall * 1000:.1f} ms, CPU {cpu * 1000:.1f} ms "
                  f"({cpu / hello_cpu:.1f}x hello-world; medians of {runs}), "
                  f"{len(loaded_objects(command))} shared objects")
        print(f"load average: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
