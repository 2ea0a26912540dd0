#!/usr/bin/env bash
# Every side-by-side table of docs/benchmarks.md, against the peers at the
# commits the docs name: DBoW3 (vocabulary load, transform, database add,
# query and memory), fbow (transform per Hamming kernel set, vocabulary
# building), DBoW2 (vocabulary building) and DLoopDetector (loop detection
# end to end). Each peer is cloned at its pinned commit into WORK and built
# there with the same flags (CMake's Release, -O3, plus -march=native); each
# harness links the binbow build given. For users with network access (or a
# mirror, PEERS_MIRROR); never run by binbow's build or CI.
#
#   bench/peers/run_all.sh [TABLE...]
#
# TABLE: dbow3 fbow dbow2 dloopdetector (default: all four). Prints the
# Markdown tables, each under the date, load average, CPU and Hamming kernel
# set of its run, and keeps a copy in WORK/tables.md.
#
# Environment: BINBOW_BUILD (a Release build tree of binbow with bin/binbow,
# src/libbinbow_core.a and the CLI's vision module; default build/), WORK
# (default $BINBOW_BUILD/peers), VOCABULARY (an existing trained .bbw from
# scripts/make_benchmark_vocabulary.sh; default: train one), PEERS_MIRROR,
# BINBOW_SHARED_DATA. Repetitions: DBOW3_REPS (3), DBOW3_ENTRIES (10000),
# FBOW_REPS (100 calls per image), BUILD_REPS (1), DLD_REPS (1). The headline
# figures of the docs come from quiet machines: check the load average
# printed with each table before comparing.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
build=$(realpath "${BINBOW_BUILD:-$repo/build}")
work=$(realpath -m "${WORK:-$build/peers}")
export BINBOW_BUILD=$build WORK=$work
export BINBOW_SHARED_DATA=${BINBOW_SHARED_DATA:-$repo/../shared/data}
tables=("$@")
[ ${#tables[@]} -gt 0 ] || tables=(dbow3 fbow dbow2 dloopdetector)
mkdir -p "$work"
# shellcheck source=common/peers.sh
source "$here/common/peers.sh"
[ -x "$build/bin/binbow" ] || { echo "run_all.sh: no $build/bin/binbow (build binbow's Release first)" >&2; exit 1; }
# One trained vocabulary for every table.
VOCABULARY=$(peer_vocabulary "$work" "$build/bin/binbow")
export VOCABULARY

{
  echo "## binbow side by side with its peers"
  echo
  echo "- binbow: $(git -C "$repo" rev-parse --short HEAD) ($build)"
  for table in "${tables[@]}"; do
    echo
    case $table in
      dbow3) REPS=${DBOW3_REPS:-3} ENTRIES=${DBOW3_ENTRIES:-10000} "$here/dbow3/run.sh" all ;;
      fbow)
        WORK=$work/fbow REPS=${FBOW_REPS:-100} BUILD_REPS=${BUILD_REPS:-1} "$here/fbow/run.sh" all
        ;;
      dbow2) REPS=${BUILD_REPS:-1} "$here/dbow2/run.sh" all ;;
      dloopdetector) REPS=${DLD_REPS:-1} BINBOW=$build/bin/binbow "$here/dloopdetector/timing.sh" "$work" ;;
      *) echo "run_all.sh: unknown table $table (dbow3, fbow, dbow2, dloopdetector)" >&2; exit 2 ;;
    esac
  done
} | tee "$work/tables.md"
