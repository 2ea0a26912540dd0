#!/usr/bin/env bash
# binbow against DBoW3 (rmsalinas/DBow3 at the pinned commit, cloned and built
# beside binbow with the peers' flags): vocabulary load, transform and the
# database (add, query, memory per entry), in one process on the same trained
# vocabulary and real ORB descriptors. Prints the Markdown tables of
# docs/benchmarks.md with the date, load and CPU.
#
#   bench/peers/dbow3/run.sh [setup|bench|all]     (default: all)
#
# Environment: BINBOW_BUILD (a Release build tree of binbow with bin/binbow
# and src/libbinbow_core.a; default build/), WORK (default
# $BINBOW_BUILD/peers), VOCABULARY (an existing trained .bbw to use; default:
# train one), BINBOW_SHARED_DATA (default ../shared/data beside the
# repository), REPS (3), TABLES (load,transform,database), ENTRIES (the
# larger database, 10000; 100000 for the 100k table, ~7 GB of memory),
# QUERIES (200), PEERS_MIRROR / DBOW3_REPO (clone source, see
# common/peers.sh).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../../.." && pwd)
# shellcheck source=../common/peers.sh
source "$here/../common/peers.sh"
build="" binbow="" # set by peer_binbow
peer_binbow dbow3/run.sh "$repo"
work=$(realpath -m "${WORK:-$build/peers}")

setup() {
  mkdir -p "$work/src" "$work/build"
  # Every file but the ORB vocabulary it ships (Git LFS-sized; not used).
  peer_clone rmsalinas/DBow3 "$work/src/DBow3" '\.dbow3$'
  [ -f "$work/install/lib/libDBoW3.so" ] ||
    peer_cmake "$work/src/DBow3" "$work/build/DBow3" "$work/install" -DBUILD_UTILS=OFF
  local vocabulary
  vocabulary=$(peer_vocabulary "$work" "$binbow")
  for ext in dbow3 txt; do
    [ -f "${vocabulary%.bbw}.$ext" ] || "$binbow" convert "$vocabulary" "${vocabulary%.bbw}.$ext" >/dev/null
  done
  cmake -S "$here" -B "$work/build/dbow3-harness" -G Ninja -DBINBOW_CORE_LIBRARY="$build/src/libbinbow_core.a" \
    -DPEERS_PREFIX="$work/install" >/dev/null
  cmake --build "$work/build/dbow3-harness" >/dev/null
}

bench() {
  local vocabulary=$work/vocab/orb_k10l6_benchmark
  echo "### binbow / DBoW3 @${PEER_COMMIT[rmsalinas/DBow3]:0:7}"
  echo
  peer_header "$binbow"
  echo
  "$work/build/dbow3-harness/harness" --bbw "$vocabulary.bbw" --dbow3 "$vocabulary.dbow3" \
    --text "$vocabulary.txt" --reps "${REPS:-3}" --tables "${TABLES:-load,transform,database}" \
    --entries "${ENTRIES:-10000}" --queries "${QUERIES:-200}"
  echo
  echo "- finished: $(date -u '+%H:%M UTC'); load average: $(cut -d' ' -f1-3 /proc/loadavg)"
}

case "${1:-all}" in
  setup) setup ;;
  bench) bench ;;
  all) setup; bench ;;
  *) echo "usage: $0 [setup|bench|all]" >&2; exit 2 ;;
esac
