#!/usr/bin/env bash
# Trains the benchmark vocabulary: k=10, L=6 ORB on every training photograph
# (scripts/training_images.sh --all), ~1.65M descriptors → ~540k words, the
# size class of ORB-SLAM's ORBvoc.txt. Not shipped (~25 MB); bench_transform
# times transform on it when BINBOW_BENCH_VOCABULARY names the file.
#
#   scripts/make_benchmark_vocabulary.sh [BUILD_DIR] [OUT]
#
# BUILD_DIR: where bin/binbow is (default: build); OUT: the .bbw to write
# (default: build/orb_k10l6_benchmark.bbw).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out=${2:-$build/orb_k10l6_benchmark.bbw}
binbow="$build/bin/binbow"
[ -x "$binbow" ] || { echo "build binbow first: $binbow is missing" >&2; exit 1; }

list=$(mktemp --suffix=.txt)
trap 'rm -f "$list"' EXIT
scripts/training_images.sh --all > "$list"
"$binbow" build-vocab --descriptor orb --branching 10 --levels 6 --seed 1 \
  --features-per-image 4000 -o "$out" "$list"
echo "BINBOW_BENCH_VOCABULARY=$out build/bin/bench_transform --benchmark_filter=Trained"
