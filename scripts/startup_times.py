#!/usr/bin/env python3
"""Start-up time of the binbow CLI beside a C++ hello-world linked with the
same standard library: the median wall and CPU (user + system) times of N
runs of each command, and the shared objects each loads (LD_DEBUG=files).
On a loaded machine the CPU time is the steadier figure.

    scripts/startup_times.py build/bin/binbow [N]
"""
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def median_seconds(command, runs):
    """Median wall and CPU seconds of `runs` runs of `command`."""
    walls, cpus = [], []
    for _ in range(runs):
        start = time.perf_counter()
        child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        _, status, usage = os.wait4(child.pid, 0)
        walls.append(time.perf_counter() - start)
        cpus.append(usage.ru_utime + usage.ru_stime)
        if status != 0:
            sys.exit(f"{command} failed ({status})")
    return statistics.median(walls), statistics.median(cpus)


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
    vocabulary = Path(__file__).resolve().parents[1] / "data" / "vocab" / "orb_default.bbw"
    with tempfile.TemporaryDirectory() as scratch:
        hello = Path(scratch) / "hello"
        source = Path(scratch) / "hello.cpp"
        source.write_text('#include <iostream>\nint main() { std::cout << "hello\\n"; }\n')
        subprocess.run([os.environ.get("CXX", "c++"), "-O2", str(source), "-o", str(hello)],
                       check=True)
        for name, command in (("hello-world (C++, libstdc++)", [str(hello)]),
                              ("binbow --version", [cli, "--version"]),
                              ("binbow info orb_default.bbw", [cli, "info", str(vocabulary)])):
            wall, cpu = median_seconds(command, runs)
            print(f"{name}: wall {wall * 1000:.1f} ms, CPU {cpu * 1000:.1f} ms (medians of "
                  f"{runs}), {len(loaded_objects(command))} shared objects")


if __name__ == "__main__":
    main()
