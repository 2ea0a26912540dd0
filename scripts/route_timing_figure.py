#!/usr/bin/env python3
"""Time per frame of `binbow detect-loops` against the number of frames seen,
over a long route made by `binbow make-route` (docs/benchmarks.md, "Long
routes"). Makes the route, runs detection with the bundled ORB and BRIEF
vocabularies and their defaults, reads the per-frame stage timings of each
run record (<loops>.run.json) and plots a running median.

    scripts/route_timing_figure.py [--build build] [--frames 10000]
        [--output docs/figures/route_time_per_frame.png]

Needs build/bin/binbow, python3-matplotlib and the route photographs
(scripts/route_photographs.sh names their Debian packages). Prints the
median milliseconds per frame over each window of frames.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Stages after feature extraction: what grows with the frames seen.
SEARCH_STAGES = ("transform", "query", "islands", "verification", "insertion")


def run(command, **kwargs):
    print("+", " ".join(command), file=sys.stderr, flush=True)
    return subprocess.run(command, check=True, **kwargs)


def running_median(values, window):
    half = window // 2
    return [statistics.median(values[max(0, i - half):i + half + 1]) for i in range(len(values))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default=os.path.join(ROOT, "build"))
    parser.add_argument("--frames", type=int, default=10000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--window", type=int, default=200, help="frames per running median")
    parser.add_argument("--output", default=os.path.join(ROOT, "docs/figures/route_time_per_frame.png"))
    args = parser.parse_args()
    binbow = os.path.join(args.build, "bin", "binbow")
    if not os.access(binbow, os.X_OK):
        sys.exit(f"{sys.argv[0]}: {binbow} not found; build the binbow target first")

    with tempfile.TemporaryDirectory() as work:
        photographs = os.path.join(work, "photographs.txt")
        with open(photographs, "w") as out:
            run(["bash", os.path.join(ROOT, "scripts/route_photographs.sh")], stdout=out)
        route = os.path.join(work, "route")
        run([binbow, "make-route", "--frames", str(args.frames), "--seed", str(args.seed),
             "-o", route, photographs])
        series = {}
        for descriptor in ("orb", "brief"):
            loops = os.path.join(work, descriptor + ".csv")
            run([binbow, "detect-loops", "--descriptor", descriptor, "-o", loops,
                 os.path.join(route, "frames")])
            with open(loops + ".run.json") as f:
                timing = json.load(f)["timing_ms"]
            frames = len(timing["features"])
            total = [sum(timing[s][i] for s in timing) for i in range(frames)]
            search = [sum(timing[s][i] for s in SEARCH_STAGES) for i in range(frames)]
            series[descriptor] = (total, search)

    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=100)
    colours = {"orb": "tab:blue", "brief": "tab:orange"}
    for descriptor, (total, search) in series.items():
        x = range(1, len(total) + 1)
        ax.plot(x, running_median(total, args.window), color=colours[descriptor],
                label=f"{descriptor.upper()}: whole frame")
        ax.plot(x, running_median(search, args.window), color=colours[descriptor], linestyle="--",
                label=f"{descriptor.upper()}: after features (transform, query, islands, "
                      "verification, insertion)")
    ax.set_xlabel("frames seen")
    ax.set_ylabel(f"ms per frame (running median of {args.window})")
    ax.set_title(f"binbow detect-loops on a {args.frames:,}-frame make-route route, defaults")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
    fig.savefig(args.output)
    print(f"figure: {args.output}")
    for descriptor, (total, search) in series.items():
        for start in range(0, len(total), len(total) // 5):
            end = min(len(total), start + len(total) // 5)
            print(f"{descriptor} frames {start + 1}-{end}: median {statistics.median(total[start:end]):.2f}"
                  f" ms whole, {statistics.median(search[start:end]):.2f} ms after features")


if __name__ == "__main__":
    main()
