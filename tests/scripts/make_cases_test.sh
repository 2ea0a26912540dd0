#!/usr/bin/env bash
# scripts/make_cases.py: the case list with its parts, the same frames and
# ground truth for the same seed, other frames for another seed, and the
# ground truth of a re-timed revisit derived from the sequence's.
#   make_cases_test.sh MAKE_CASES SAMPLES_DIR GT_PAIRS WORK_DIR
set -euo pipefail
make_cases=$1 samples=$2 pairs=$3 work=$4
fail() { echo "make_cases_test: $*" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work"

listed=$("$make_cases" --seed 1 --list)
[ "$(wc -l <<<"$listed")" -ge 14 ] || fail "too few cases listed: $listed"
grep -qx "rotate_5 tuning" <<<"$listed" || fail "rotate_5 is not a tuning case: $listed"
grep -qx "revisit_fast validation" <<<"$listed" || fail "revisit_fast not listed: $listed"
if "$make_cases" --seed 1 "$samples" "$pairs" "$work/x" no_such_case 2>"$work/err"; then
  fail "an unknown case was accepted"
fi
grep -q "unknown case no_such_case" "$work/err" || fail "unclear error: $(cat "$work/err")"

# A 12-frame sequence whose frames 8-12 (1-based) revisit frames 2-6.
mini="$work/mini"
mkdir -p "$mini"
for i in $(seq 1 12); do cp "$samples/$i.jpg" "$mini/$i.jpg"; done
{
  echo "# 1-based"
  for q in 8 9 10 11 12; do echo "$q $((q - 6))"; done
} >"$mini/pairs.txt"

for run in a b; do
  "$make_cases" --seed 7 "$mini" "$mini/pairs.txt" "$work/$run" rotate_5 revisit_fast >/dev/null
done
"$make_cases" --seed 8 "$mini" "$mini/pairs.txt" "$work/other" rotate_5 >/dev/null
diff -r "$work/a/rotate_5/frames" "$work/b/rotate_5/frames" >/dev/null || fail "seed 7 made other frames"
diff -r "$work/a/revisit_fast" "$work/b/revisit_fast" >/dev/null || fail "seed 7 made another revisit"
! diff -q "$work/a/rotate_5/frames/000005.png" "$work/other/rotate_5/frames/000005.png" \
  >/dev/null || fail "seeds 7 and 8 made the same rotation"

# The revisit at twice the speed: the first visit whole (0-6), every other
# frame of the second (7, 9, 11 become 7, 8, 9), each keeping its loops.
frames=$(ls "$work/a/revisit_fast/frames" | wc -l)
[ "$frames" -eq 10 ] || fail "revisit_fast has $frames frames, not 7 + 3"
gt="$work/a/revisit_fast/ground_truth.txt"
head -1 "$gt" | grep -q "0-based" || fail "$gt does not say 0-based"
got=$(grep -v '^#' "$gt" | sort -n | tr '\n' ',')
[ "$got" = "7 1,8 3,9 5," ] || fail "revisit_fast's ground truth is '$got', not '7 1,8 3,9 5,'"
echo "make_cases_test: passed"
