#!/usr/bin/env bash
# binbow against fbow: transform -> BoW vector on the same trained vocabulary
# (binbow's, written as .fbow by `binbow convert` and read by fbow's loader)
# and the same real ORB descriptors, calls interleaved in one process, per
# Hamming kernel (BINBOW_HAMMING_KERNEL), one process per kernel, two rounds
# in alternating order; and vocabulary building against fbow's creator. fbow
# is cloned at a pinned commit into WORK and built there with -O3
# -march=native; nothing of it enters binbow's build.
#
#   bench/peers/fbow/run.sh [setup|bench|build|callgrind|all]     (default: all)
#
# bench prints the transform table, build the vocabulary-building table, all
# does setup, bench and build (callgrind only when asked: it takes long).
# Environment: BINBOW_BUILD (a Release build tree of binbow with bin/binbow
# and src/libbinbow_core.a; default build/), WORK (default
# $BINBOW_BUILD/peers/fbow), VOCABULARY (an existing trained .bbw; default:
# train one), BINBOW_SHARED_DATA (default ../shared/data beside the
# repository), REPS (100 calls per image), BUILD_REPS (1), NICE (0), KERNELS
# (default: the kernel sets this CPU has of generic popcnt avx2 avx512),
# PEERS_MIRROR / FBOW_REPO (clone source, see common/peers.sh). Needs
# OpenCV's development files and, for callgrind, valgrind.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
main=$(cd "$here/../../.." && pwd)
# shellcheck source=../common/peers.sh
source "$here/../common/peers.sh"
build_dir=$(realpath "${BINBOW_BUILD:-$main/build}")
work=$(realpath -m "${WORK:-$build_dir/peers/fbow}")
binbow="$build_dir/bin/binbow"
export BINBOW_SHARED_DATA=${BINBOW_SHARED_DATA:-$main/../shared/data}
reps=${REPS:-100}
nice_level=${NICE:-0}
for f in "$binbow" "$build_dir/src/libbinbow_core.a"; do
  [ -e "$f" ] || { echo "fbow/run.sh: no $f (build binbow's Release first, or set BINBOW_BUILD)" >&2; exit 1; }
done
if [ -n "${KERNELS:-}" ]; then
  read -r -a kernels <<<"$KERNELS"
else
  kernels=()
  for k in generic popcnt avx2 avx512; do
    if BINBOW_HAMMING_KERNEL=$k "$binbow" info --system 2>/dev/null | grep -q "^hamming_kernel: $k$"; then
      kernels+=("$k")
    fi
  done
fi
mkdir -p "$work"
cd "$work"

setup() {
  # Every file of the pinned commit but orb_mur.fbow, which is stored with Git LFS.
  peer_clone rmsalinas/fbow fbow 'orb_mur\.fbow$'
  { cmake -S fbow -B fbow-build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS="$PEER_CXX_FLAGS" \
    -DBUILD_UTILS=OFF -DBUILD_SHARED_LIBS=ON && cmake --build fbow-build; } >fbow-build.log 2>&1 ||
    { echo "fbow/run.sh: building fbow failed; see $work/fbow-build.log" >&2; exit 1; }
  # binbow's static core library copied, so that a rebuild cannot change it mid-run.
  mkdir -p binbow-lib && cp "$build_dir/src/libbinbow_core.a" binbow-lib/
  git -C "$main" rev-parse HEAD >binbow-lib/COMMIT
  peer_vocabulary "$work" "$binbow" >/dev/null
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
  grep -q "^RESULT" "$log" || { echo "fbow/run.sh: no result in $work/$log" >&2; return 1; }
}

bench() {
  mkdir -p logs
  echo "### binbow / fbow @${PEER_COMMIT[rmsalinas/fbow]:0:7}: transform, per kernel set"
  echo
  peer_header "$binbow"
  for v in orb_k10l6_benchmark orb_default; do
    for k in "${kernels[@]}"; do one $v "$k" binbow >/dev/null; done
    for ((i = ${#kernels[@]} - 1; i >= 0; i--)); do one $v "${kernels[i]}" fbow >/dev/null; done
  done
  echo
  echo "Thread CPU time per call (1000 descriptors), medians of $reps interleaved calls per image;"
  echo "each figure: the two rounds (binbow first, fbow first); every word and BoW vector checked equal."
  echo
  echo "| vocabulary | kernel set | binbow | fbow | fbow / binbow | per pass |"
  echo "| --- | --- | ---: | ---: | ---: | ---: |"
  for v in orb_k10l6_benchmark orb_default; do
    for k in "${kernels[@]}"; do
      cat logs/$v.$k.binbow.log logs/$v.$k.fbow.log | awk -v v=$v -v k="$k" '
        function field(name,   i, kv) {
          for (i = 1; i <= NF; i++) { split($i, kv, "="); if (kv[1] == name) return kv[2] }
        }
        function range(a, b, unit) { return (a == b ? a : (a < b ? a "–" b : b "–" a)) unit }
        /^RESULT/ { n++; b[n] = field("binbow_us"); f[n] = field("fbow_us"); r[n] = field("ratio")
                    lo[n] = field("pass_ratio_min"); hi[n] = field("pass_ratio_max") }
        END {
          if (n != 2) { print "| " v " | " k " | missing: see logs/ | | | |"; exit }
          printf "| %s | %s | %s | %s | **%s** | %s |\n", v, k, range(b[1], b[2], " µs"),
                 range(f[1], f[2], " µs"), range(r[1], r[2], "x"),
                 (lo[1] < lo[2] ? lo[1] : lo[2]) "–" (hi[1] > hi[2] ? hi[1] : hi[2]) "x" }'
    done
  done
  echo
  echo "- finished: $(date -u '+%H:%M UTC'); load average: $(cut -d' ' -f1-3 /proc/loadavg)"
}

# Vocabulary building, k=10 L=5 on 150k ORB: binbow and fbow's creator.
build_table() {
  echo
  echo "### binbow / fbow @${PEER_COMMIT[rmsalinas/fbow]:0:7}: vocabulary building"
  echo
  peer_header "$binbow"
  echo
  nice -n "$nice_level" ./build/build_harness --reps "${BUILD_REPS:-1}"
  echo
  echo "- finished: $(date -u '+%H:%M UTC'); load average: $(cut -d' ' -f1-3 /proc/loadavg)"
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
  build) build_table ;;
  callgrind) callgrind ;;
  all) setup; bench; build_table ;;
  *) echo "usage: $0 [setup|bench|build|callgrind|all]" >&2; exit 2 ;;
esac
