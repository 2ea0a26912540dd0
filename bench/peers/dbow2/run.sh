#!/usr/bin/env bash
# binbow against DBoW2 (dorian3d/DBoW2 at the pinned commit, cloned and built
# beside binbow with the peers' flags) building a vocabulary: k=10 L=5 from
# the same 150,000 real ORB descriptors, CPU time and quantisation error.
# Prints the Markdown table with the date, load and CPU.
#
#   bench/peers/dbow2/run.sh [setup|bench|all]     (default: all)
#
# Environment: BINBOW_BUILD (a Release build tree of binbow with bin/binbow
# and src/libbinbow_core.a; default build/), WORK (default
# $BINBOW_BUILD/peers), BINBOW_SHARED_DATA (default ../shared/data beside the
# repository), REPS (1; DBoW2 takes 5–15 s of CPU a build), PEERS_MIRROR /
# DBOW2_REPO (clone source, see common/peers.sh).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../../.." && pwd)
# shellcheck source=../common/peers.sh
source "$here/../common/peers.sh"
build="" binbow="" # set by peer_binbow
peer_binbow dbow2/run.sh "$repo"
work=$(realpath -m "${WORK:-$build/peers}")

setup() {
  mkdir -p "$work/src" "$work/build"
  peer_clone dorian3d/DBoW2 "$work/src/DBoW2"
  [ -f "$work/install/lib/libDBoW2.so" ] ||
    peer_cmake "$work/src/DBoW2" "$work/build/DBoW2" "$work/install" -DBUILD_Demo=OFF
  cmake -S "$here" -B "$work/build/dbow2-harness" -G Ninja -DBINBOW_CORE_LIBRARY="$build/src/libbinbow_core.a" \
    -DPEERS_PREFIX="$work/install" >/dev/null
  cmake --build "$work/build/dbow2-harness" >/dev/null
}

bench() {
  echo "### binbow / DBoW2 @${PEER_COMMIT[dorian3d/DBoW2]:0:7}: vocabulary building"
  echo
  peer_header "$binbow"
  echo
  "$work/build/dbow2-harness/build_harness" --reps "${REPS:-1}"
  echo
  echo "- finished: $(date -u '+%H:%M UTC'); load average: $(cut -d' ' -f1-3 /proc/loadavg)"
}

case "${1:-all}" in
  setup) setup ;;
  bench) bench ;;
  all) setup; bench ;;
  *) echo "usage: $0 [setup|bench|all]" >&2; exit 2 ;;
esac
