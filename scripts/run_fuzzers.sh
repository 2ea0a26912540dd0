#!/usr/bin/env bash
# Builds every libFuzzer target (fuzz/fuzz_*.cpp) with clang, AddressSanitizer
# and UndefinedBehaviorSanitizer, then runs each for SECONDS (default 15; 21
# targets, JOBS at a time) on its corpus fuzz/corpus/<name>/ and prints the coverage reached.
# Fails if any target crashes, leaks, hangs, exceeds 2 GiB, or makes a single
# allocation over 512 MiB (inputs are at most a few KiB, see max_len_of: such
# an allocation means a reader trusted a header), and if a seed is longer than
# its target's input limit (libFuzzer would cut it, and a cut .bbdb seed never
# loads). New inputs go to the build directory, not the repository; a crashing
# input is saved there as <build>/fuzz-artifacts/<name>-crash-*: fix the bug,
# then copy the input into fuzz/corpus/<name>/ so ctest (FuzzCorpus.* in
# test_formats and test_loop) replays it from then on.
#
# A build folder (BINBOW_FUZZ_BUILD_DIR) already configured with
# -DBINBOW_BUILD_FUZZ=ON is used as it is, tests and all: CI fuzzes its
# sanitizer build.
#
# Usage: scripts/run_fuzzers.sh [SECONDS]   (env: BINBOW_FUZZ_BUILD_DIR, JOBS)
set -euo pipefail

seconds="${1:-15}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BINBOW_FUZZ_BUILD_DIR:-$root/build-fuzz}"
jobs="${JOBS:-2}"

if ! command -v clang++ >/dev/null; then
  echo "run_fuzzers: clang++ is needed (Debian: clang and libclang-rt-14-dev)" >&2
  exit 1
fi

mkdir -p "$build"
if ! grep -qs '^BINBOW_BUILD_FUZZ:BOOL=ON$' "$build/CMakeCache.txt"; then
  # -O1 and line tables only, as libFuzzer's documentation suggests: reports
  # still name files and lines, and it compiles far faster than -O2 -g.
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only -DNDEBUG" \
    -DCMAKE_CXX_COMPILER=clang++ -DBINBOW_BUILD_FUZZ=ON -DBINBOW_BUILD_TESTS=OFF \
    -DBINBOW_BUILD_BENCH=OFF >"$build/configure.log" 2>&1 || {
    cat "$build/configure.log" >&2
    exit 1
  }
fi
targets=()
for source in "$root"/fuzz/fuzz_*.cpp; do
  targets+=("$(basename "$source" .cpp)")
done
cmake --build "$build" -j "$jobs" --target "${targets[@]}"

# The longest input of each target (-max_len): room for a valid file a few
# times its seeds' size, small enough that every input runs fast.
max_len_of() {
  case "$1" in
    gt_pairs) echo 1024 ;;
    params_json | params_yaml | gt_mat | loops_csv) echo 2048 ;;
    orbslam_text | dbow2_yaml | gzip | tar | loop_run | bbov | bbld) echo 8192 ;;
    *) echo 4096 ;;
  esac
}

# Runs one target; prints its line and returns non-zero if it failed.
fuzz_one() {
  local target=$1 name binary corpus work artifacts max_len long_seeds
  name="${target#fuzz_}"
  binary="$(find "$build" -type f -name "$target" -perm -u+x | head -n 1)"
  corpus="$root/fuzz/corpus/$name"
  work="$build/fuzz-work/$name"
  artifacts="$build/fuzz-artifacts"
  mkdir -p "$corpus" "$work" "$artifacts"
  max_len="$(max_len_of "$name")"
  long_seeds="$(find "$corpus" -type f -size +"$max_len"c)"
  if [[ -n "$long_seeds" ]]; then
    echo "run_fuzzers: seeds longer than -max_len=$max_len of $target would be cut:" >&2
    echo "$long_seeds" >&2
    return 1
  fi
  if ! "$binary" -max_total_time="$seconds" -max_len="$max_len" -timeout=10 -rss_limit_mb=2048 \
      -malloc_limit_mb=512 \
      -print_final_stats=1 -artifact_prefix="$artifacts/$name-" "$work" "$corpus" \
      >"$build/fuzz-$name.log" 2>&1; then
    echo "== $target FAILED:" >&2
    tail -n 40 "$build/fuzz-$name.log" >&2
    return 1
  fi
  echo "== $target: ${seconds}s on $(find "$corpus" -type f | wc -l) seed(s), -max_len=$max_len," \
    "$(grep -oE "cov: [0-9]+" "$build/fuzz-$name.log" | tail -n 1)" \
    "$(grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$build/fuzz-$name.log" | tr '\n' ' ')"
}

# JOBS targets at a time: each libFuzzer process runs on one core.
failed=()
pids=()
names=()
reap() {
  local i=$1
  wait "${pids[$i]}" || failed+=("${names[$i]}")
}
for target in "${targets[@]}"; do
  if ((${#pids[@]} >= jobs)); then
    reap 0
    pids=("${pids[@]:1}")
    names=("${names[@]:1}")
  fi
  fuzz_one "$target" &
  pids+=($!)
  names+=("$target")
done
for i in "${!pids[@]}"; do reap "$i"; done

if ((${#failed[@]})); then
  echo "run_fuzzers: FAILED: ${failed[*]} (inputs in $build/fuzz-artifacts)" >&2
  exit 1
fi
echo "run_fuzzers: ${#targets[@]} targets ran ${seconds}s each without a crash"
