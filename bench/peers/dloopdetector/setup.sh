# shellcheck shell=bash
# Sourced by side_by_side.sh and timing.sh: dld_setup WORK clones
# DLoopDetector, DLib and DBoW2 at their pinned commits into WORK/src, builds
# and installs DLib and DBoW2 into WORK/install with the peers' flags, builds
# our driver (dld_run) into WORK/build/driver and converts binbow's bundled
# vocabularies to DBoW2 YAML beside. GIT_BASE (e.g. a folder holding the
# three repositories) is still read for the clone source, before
# PEERS_MIRROR.
dld_here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=../common/peers.sh
source "$dld_here/../common/peers.sh"

dld_setup() {
  local work=$1 binbow=$2 repo
  repo=$(cd "$dld_here/../../.." && pwd)
  if [ -n "${GIT_BASE:-}" ]; then
    export DLOOPDETECTOR_REPO=${DLOOPDETECTOR_REPO:-$GIT_BASE/DLoopDetector}
    export DLIB_REPO=${DLIB_REPO:-$GIT_BASE/DLib} DBOW2_REPO=${DBOW2_REPO:-$GIT_BASE/DBoW2}
  fi
  mkdir -p "$work/src" "$work/build"
  peer_clone dorian3d/DLoopDetector "$work/src/DLoopDetector"
  peer_clone dorian3d/DLib "$work/src/DLib"
  peer_clone dorian3d/DBoW2 "$work/src/DBoW2"
  # DLib and DBoW2 build unpatched (OpenCV 4.6, GCC 12); DLoopDetector is used
  # as headers (its own CMakeLists downloads its dependencies).
  [ -f "$work/install/lib/libDLib.so" ] || peer_cmake "$work/src/DLib" "$work/build/DLib" "$work/install"
  [ -f "$work/install/lib/libDBoW2.so" ] ||
    peer_cmake "$work/src/DBoW2" "$work/build/DBoW2" "$work/install" -DBUILD_Demo=OFF
  cmake -S "$dld_here" -B "$work/build/driver" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CXX_FLAGS="$PEER_CXX_FLAGS" -DPEERS_PREFIX="$work/install" \
    -DDLD_SRC="$work/src/DLoopDetector" >/dev/null
  cmake --build "$work/build/driver" >/dev/null
  local descriptor format
  for descriptor in orb brief; do
    format=bytes
    [ $descriptor = brief ] && format=bits
    [ -f "$work/${descriptor}_default.yml.gz" ] ||
      "$binbow" -q convert "$repo/data/vocab/${descriptor}_default.bbw" \
        "$work/${descriptor}_default.yml.gz" --descriptors $format >/dev/null
  done
}
