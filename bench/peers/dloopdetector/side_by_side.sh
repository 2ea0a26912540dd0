#!/usr/bin/env bash
# binbow and DLoopDetector side by side on one image sequence, with the same
# vocabularies (binbow's bundled ones, converted to DBoW2 YAML), evaluated by
# `binbow evaluate` against the same ground truth. Nothing here is part of
# binbow's build or CI: it clones the peers at pinned commits into WORK and
# builds them there.
#
#   bench/peers/dloopdetector/side_by_side.sh WORK FRAMES GROUND_TRUTH
#
# WORK          a folder of its own (sources, builds, results)
# FRAMES        an image folder (natural order: 2.jpg before 10.jpg)
# GROUND_TRUTH  anything `binbow evaluate --gt` reads
#
# Environment: BINBOW (default: build/bin/binbow of this repository),
# GIT_BASE (the three repositories are cloned from GIT_BASE/NAME; default:
# PEERS_MIRROR or GitHub, see common/peers.sh), PATTERN (DLoopDetector's BRIEF pattern file, default the
# shared data's vins-lite-brief-vocab/brief_pattern.yml, which binbow's BRIEF
# uses too).
#
# Runs, each on one thread: binbow's defaults; DLoopDetector as its demo
# sets it (Parameters(rows, cols, 1), use_nss, alpha 0.3, k 1, GEOM_DI with
# di_levels 2) and with its constructor's k 3; binbow with DLoopDetector's
# rules (dld_rules_k1.json: k 1, no strong-fit or corroboration rules, no
# degeneracy test, no exhaustive retry, OpenCV's RANSAC, only the island's
# best entry checked, no localisation). ORB: cv::ORB with
# binbow's settings on both sides; BRIEF: DLoopDetector's FAST + BRIEF256
# pipeline (every FAST corner at threshold 20) against binbow's (the 300
# strongest at threshold 10 whose tests lie inside the image). DLib seeds its
# RANSAC from the clock; the driver seeds it with 0 so that runs repeat.
# Prints one Markdown row per run: precision, recall, queries found, false
# loops.
set -euo pipefail

if [ $# -ne 3 ]; then
  sed -n '2,30p' "$0" | sed 's/^# \{0,1\}//'
  exit 1
fi
work=$(realpath -m "$1")
frames=$(realpath "$2")
ground_truth=$(realpath "$3")
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../../.." && pwd)
binbow=${BINBOW:-$repo/build/bin/binbow}
pattern=${PATTERN:-$repo/../shared/data/vins-lite-brief-vocab/brief_pattern.yml}
[ -x "$binbow" ] || { echo "side_by_side.sh: no binbow at $binbow (build it, or set BINBOW)" >&2; exit 1; }
[ -f "$pattern" ] || { echo "side_by_side.sh: no BRIEF pattern at $pattern (set PATTERN)" >&2; exit 1; }

# shellcheck source=setup.sh
source "$here/setup.sh"
dld_setup "$work" "$binbow"
driver=$work/build/driver/dld_run
mkdir -p "$work/results"

row() {  # label loops.csv
  local result
  result=$("$binbow" evaluate --gt "$ground_truth" "$2")
  value() { sed -n "s/^$1: //p" <<<"$result"; }
  printf '| %s | %.3f | %.3f | %s / %s | %s |\n' "$1" "$(value precision)" "$(value recall)" \
    "$(value 'queries found')" "$(value 'queries with a loop')" "$(value 'false positives')"
}

echo "| run | precision | recall | queries found / with a loop | false loops |"
echo "| --- | ---: | ---: | ---: | ---: |"
for descriptor in orb brief; do
  vocabulary=$repo/data/vocab/${descriptor}_default.bbw
  out=$work/results/$descriptor
  "$binbow" detect-loops --threads 1 --descriptor $descriptor --vocab "$vocabulary" \
    -o "$out.binbow.csv" "$frames" >/dev/null 2>&1
  row "binbow $descriptor, defaults" "$out.binbow.csv"
  "$binbow" detect-loops --threads 1 --descriptor $descriptor --vocab "$vocabulary" \
    --params "$here/dld_rules_k1.json" -o "$out.binbow_dld_rules.csv" "$frames" >/dev/null 2>&1
  row "binbow $descriptor, DLoopDetector's rules, k 1" "$out.binbow_dld_rules.csv"
  extra=()
  [ $descriptor = brief ] && extra=(--pattern "$pattern")
  for k in 1 3; do
    "$driver" --descriptor $descriptor --vocab "$work/${descriptor}_default.yml.gz" "${extra[@]}" \
      --seed 0 --k $k -o "$out.dld_k$k.csv" "$frames" >/dev/null 2>&1
    row "DLoopDetector $descriptor, k $k" "$out.dld_k$k.csv"
  done
done
