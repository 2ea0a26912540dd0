#!/usr/bin/env bash
# binbow against fbow: transform -> BoW vector on the same trained vocabulary
# (binbow's, written as .fbow by `binbow convert` and read by fbow's loader)
# and the same real ORB descriptors, calls interleaved in one process, per
# Hamming kernel (BINBOW_HAMMING_KERNEL), one process per kernel, two rounds
# in alternating order. fbow is cloned at a pinned commit into WORK and built
# there with -O3 -march=native; nothing of it enters binbow's build.
#
#   bench/peers/fbow/run.sh [setup|bench|callgrind|all]     (default: all)
#
# Environment: WORK (default build/peers-fbow), FBOW_REPO (default
# https://github.com/rmsalinas/fbow), BINBOW_SHARED_DATA (default
# ../shared/data beside the repository), REPS (100), NICE (0), KERNELS
# (default: generic popcnt avx2). Needs a Release build in build/ (bin/binbow,
# src/libbinbow_core.a), OpenCV's development files and, for callgrind, valgrind.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
main=$(cd "$here/../../.." && pwd)
work=$(realpath -m "${WORK:-$main/build/peers-fbow}")
binbow="$main/build/bin/binbow"
fbow_repo=${FBOW_REPO:-https://github.com/rmsalinas/fbow}
export BINBOW_SHARED_DATA=${BINBOW_SHARED_DATA:-$main/../shared/data}
reps=${REPS:-100}
nice_level=${NICE:-0}
kernels=(${KERNELS:-generic popcnt avx2})
mkdir -p "$work"
cd "$work"

setup() {
  if [ ! -d fbow ]; then
    git clone -q --no-checkout "$fbow_repo" fbow
    # Every file of the pinned commit but orb_mur.fbow, which is stored with Git LFS.
    (cd fbow && git checkout -q e148dbc -- $(git ls-tree -r --name-only e148dbc | grep -v orb_mur.fbow))
  fi
  cmake -S fbow -B fbow-build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS="-march=native" \
    -DBUILD_UTILS=OFF -DBUILD_SHARED_LIBS=ON >/dev/null
  cmake --build fbow-build >/dev/null
  # binbow's static core library copied, so that a rebuild cannot change it mid-run.
  mkdir -p binbow-lib && cp "$main/build/src/libbinbow_core.a" binbow-lib/
  git -C "$main" rev-parse HEAD >binbow-lib/COMMIT
  mkdir -p vocab
  [ -f vocab/orb_k10l6_benchmark.bbw ] ||
    bash "$main/scripts/make_benchmark_vocabulary.sh" "$main/build" "$work/vocab/orb_k10l6_benchmark.bbw"
  cp "$main/data/vocab/orb_default.bbw" vocab/
  for v in orb_k10l6_benchmark orb_default; do "$binbow" convert vocab/$v.bbw vocab/$v.fbow >/dev/null; done
  cmake -S "$here" -B build -G Ninja >/dev/null
  cmake --build build >/dev/null
}

one() {  # vocabulary kernel first
  local v=$1 k=$2 first=$3 log=logs/$1.$2.$3.log
  { echo "== vocab=$v kernel=$k first=$first"; echo "before: $(date -u '+%F %T UTC') $(uptime)"
    BINBOW_HAMMING_KERNEL=$k nice -n "$nice_level" ./build/harness --bbw vocab/$v.bbw \
      --fbow vocab/$v.fbow --reps "$reps" --first "$first" 2>&1
    echo "after: $(date -u '+%F %T UTC') $(uptime)"; } >"$log"
  grep -E "^(before|check|RESULT|after)" "$log"
}

bench() {
  mkdir -p logs
  for v in orb_k10l6_benchmark orb_default; do
    for k in "${kernels[@]}"; do one $v $k binbow; done
    for ((i = ${#kernels[@]} - 1; i >= 0; i--)); do one $v "${kernels[i]}" fbow; done
  done
}

# Instructions per descriptor (load-independent): binbow's transform per
# kernel and fbow's, 5 passes over 38 images of 1000 descriptors.
callgrind() {
  mkdir -p callgrind
  ./build/harness --bbw vocab/orb_default.bbw --fbow vocab/orb_default.fbow --check-only \
    --cache callgrind/descriptors.bin >/dev/null 2>&1
  for v in orb_k10l6_benchmark orb_default; do
    for k in "${kernels[@]}"; do
      BINBOW_HAMMING_KERNEL=$k valgrind --tool=callgrind --dump-instr=yes \
        --callgrind-out-file=callgrind/$v.binbow.$k.out --toggle-collect='binbow::Vocabulary::transform*' \
        ./build/harness --bbw vocab/$v.bbw --fbow vocab/$v.fbow --no-check --profile binbow \
        --passes 5 --cache callgrind/descriptors.bin >callgrind/$v.binbow.$k.log 2>&1
    done
    valgrind --tool=callgrind --dump-instr=yes --callgrind-out-file=callgrind/$v.fbow.out \
      --toggle-collect='fbow::Vocabulary::transform(cv::Mat const&)' \
      ./build/harness --bbw vocab/$v.bbw --fbow vocab/$v.fbow --no-check --profile fbow --passes 5 \
      --cache callgrind/descriptors.bin >callgrind/$v.fbow.log 2>&1
  done
  for f in callgrind/*.out; do
    echo "== $f"
    callgrind_annotate --inclusive=no "$f" | sed -n '/PROGRAM TOTALS/,$p' | head -14
  done
  for v in orb_k10l6_benchmark orb_default; do
    for k in "${kernels[@]}"; do
      python3 "$here/cg_instr.py" callgrind/$v.binbow.$k.out build/harness \
        "$k::(anonymous namespace)::descend_impl<32" 190000 >callgrind/$v.$k.descend.annot
    done
    python3 "$here/cg_instr.py" callgrind/$v.fbow.out fbow-build/src/libfbow.so.0.0.1 \
      'fbow::Vocabulary::transform(cv::Mat const&)' 190000 >callgrind/$v.fbow.transform.annot
  done
}

case "${1:-all}" in
  setup) setup ;;
  bench) bench ;;
  callgrind) callgrind ;;
  all) setup; bench; callgrind ;;
  *) echo "usage: $0 [setup|bench|callgrind|all]" >&2; exit 2 ;;
esac
