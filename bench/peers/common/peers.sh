# shellcheck shell=bash
# Sourced by the bench/peers scripts: where each peer is cloned from, its
# pinned commit, the compiler flags every peer is built with, and the header
# every printed table starts with. Nothing here runs at build time or in CI.
#
# Environment:
#   PEERS_MIRROR  a folder of local mirrors laid out as OWNER+NAME/repo (a
#                 bare or ordinary git repository each), for offline runs;
#                 default: clone from https://github.com/OWNER/NAME.
#   <NAME>_REPO   one peer's clone source (DBOW2_REPO, DBOW3_REPO, FBOW_REPO,
#                 DLIB_REPO, DLOOPDETECTOR_REPO), before PEERS_MIRROR.

# The pinned commits the docs' tables were measured with.
declare -A PEER_COMMIT=(
  [dorian3d/DBoW2]=3924753db6145f12618e7de09b7e6b258db93c6e
  [rmsalinas/DBow3]=c147e34d4b98c6d709d12fb046962656587261e5
  [rmsalinas/fbow]=e148dbcbd8ee1976b1b07988b5761a9171b9f01a
  [dorian3d/DLoopDetector]=f69778b12b880aa3cca0aa92cf4b8ae154ac0bfb
  [dorian3d/DLib]=16ceae3e5e6bfcc67d52297f1b0ce9c0072bb0d4
)

# Every peer: CMake's Release (-O3 -DNDEBUG) plus this.
PEER_CXX_FLAGS=${PEER_CXX_FLAGS:--march=native}

# peer_binbow SCRIPT REPO: binbow's side of a harness. Sets `build` (the
# Release build tree BINBOW_BUILD, default REPO/build) and `binbow` (its CLI),
# exports BINBOW_SHARED_DATA (default: ../shared/data beside REPO), and stops,
# naming SCRIPT, when the CLI or libbinbow_core.a is missing.
peer_binbow() {
  local script=$1 repo=$2 f
  build=$(realpath "${BINBOW_BUILD:-$repo/build}")
  binbow=$build/bin/binbow
  export BINBOW_SHARED_DATA=${BINBOW_SHARED_DATA:-$repo/../shared/data}
  for f in "$binbow" "$build/src/libbinbow_core.a"; do
    [ -e "$f" ] || { echo "$script: no $f (build binbow's Release first, or set BINBOW_BUILD)" >&2; exit 1; }
  done
}

# peer_source OWNER/NAME: the URL or folder to clone OWNER/NAME from.
peer_source() {
  local owner_name=$1 name=${1#*/} override
  override=$(echo "${name}_REPO" | tr '[:lower:]' '[:upper:]')
  if [ -n "${!override:-}" ]; then
    echo "${!override}"
  elif [ -n "${PEERS_MIRROR:-}" ]; then
    echo "$PEERS_MIRROR/${owner_name/\//+}/repo"
  else
    echo "https://github.com/$owner_name"
  fi
}

# peer_clone OWNER/NAME DEST [EXCLUDE]: DEST checked out at the pinned commit,
# without the files whose path matches the extended regular expression EXCLUDE
# (large data files kept in Git LFS or left out of mirrors, which no harness
# reads). An existing DEST at that commit is reused.
peer_clone() {
  local owner_name=$1 dest=$2 exclude=${3:-} commit=${PEER_COMMIT[$1]}
  if [ ! -d "$dest/.git" ]; then
    git clone -q --no-checkout "$(peer_source "$owner_name")" "$dest"
    git -C "$dest" update-ref --no-deref HEAD "$commit"
    git -C "$dest" ls-tree -r -z --name-only "$commit" |
      { if [ -n "$exclude" ]; then grep -z -v -E "$exclude"; else cat; fi; } |
      xargs -0 git -C "$dest" checkout -q "$commit" --
  fi
  # A checkout left at another commit would silently change the figures.
  [ "$(git -C "$dest" rev-parse HEAD)" = "$commit" ] || {
    echo "peers: $dest is not at $owner_name @$commit" >&2
    return 1
  }
}

# peer_cmake SRC BUILD PREFIX [CMAKE ARGS...]: configures, builds and installs
# a peer into PREFIX with the common flags; its output goes to BUILD.log.
peer_cmake() {
  local src=$1 build=$2 prefix=$3
  shift 3
  { cmake -S "$src" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS="$PEER_CXX_FLAGS" \
    -DCMAKE_INSTALL_PREFIX="$prefix" "$@" &&
    cmake --build "$build" -j"${JOBS:-2}" && cmake --install "$build"; } >"$build.log" 2>&1 || {
    echo "peers: building $src failed; see $build.log" >&2
    return 1
  }
}

# peer_header BINBOW: the lines every table is printed under: when, how loaded,
# which CPU, which Hamming kernel set, which binbow commit.
peer_header() {
  local binbow=$1
  echo "- date: $(date -u '+%F %H:%M UTC'); load average: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
  local kernel
  kernel=$("$binbow" info --system 2>/dev/null | sed -n 's/^hamming_kernel: //p')
  [ -z "${BINBOW_HAMMING_KERNEL:-}" ] || kernel="$kernel (forced by BINBOW_HAMMING_KERNEL)"
  echo "- CPU: $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -1); binbow's Hamming kernel set: $kernel"
}

# peer_vocabulary WORK BINBOW: the trained benchmark vocabulary (k=10 L=6
# ORB, ~540k words) as WORK/vocab/orb_k10l6_benchmark.bbw, echoing its path:
# a copy of $VOCABULARY when set, else trained by
# scripts/make_benchmark_vocabulary.sh (about 10 minutes on 2 cores; it
# installs the training photographs' Debian packages when missing).
peer_vocabulary() {
  local work=$1 binbow=$2 out=$1/vocab/orb_k10l6_benchmark.bbw
  local repo
  repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)
  mkdir -p "$work/vocab"
  if [ ! -f "$out" ]; then
    if [ -n "${VOCABULARY:-}" ]; then
      cp "$VOCABULARY" "$out"
    else
      bash "$repo/scripts/make_benchmark_vocabulary.sh" "$(dirname "$(dirname "$binbow")")" "$out" >&2
    fi
  fi
  echo "$out"
}
