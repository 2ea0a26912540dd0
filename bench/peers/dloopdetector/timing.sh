#!/usr/bin/env bash
# binbow and DLoopDetector end to end, features included: each sequence's
# frames read, decoded, described (ORB, 1000, binbow's settings on both
# sides) and run through the detector, with binbow's bundled orb_default
# vocabulary (DLoopDetector reads it as DBoW2 YAML from `binbow convert`).
# DLoopDetector: our driver dld_run, Parameters(rows, cols, frequency) with
# 1 Hz for an image folder and 10 Hz for a video, as binbow picks them; its
# time is the frame loop's, without its vocabulary load. binbow:
# `binbow detect-loops` with its defaults, `--threads 1` and `--threads 2`;
# its time is the run's `done in` line. One after the other, REPS rounds.
#
#   bench/peers/dloopdetector/timing.sh WORK [SEQUENCE...]
#
# WORK      a folder of its own (sources, builds, results), as side_by_side.sh
# SEQUENCE  an image folder or a video file; default: the shared data's
#           rtabmap-samples and OpenCV's vtest.avi (Debian's opencv-doc)
#
# Environment: BINBOW (default: build/bin/binbow of this repository), REPS
# (1), NICE (0), BINBOW_SHARED_DATA, PEERS_MIRROR / GIT_BASE / <NAME>_REPO
# (clone sources, see common/peers.sh and setup.sh). Prints a Markdown table:
# wall times (min–max (median) over the rounds), the ratios DLoopDetector /
# binbow of the medians, process CPU times and the loops each found.
set -euo pipefail

if [ $# -lt 1 ]; then
  sed -n '2,24p' "$0" | sed 's/^# \{0,1\}//'
  exit 1
fi
work=$(realpath -m "$1")
shift
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../../.." && pwd)
binbow=${BINBOW:-$repo/build/bin/binbow}
shared=${BINBOW_SHARED_DATA:-$repo/../shared/data}
reps=${REPS:-1}
nice_level=${NICE:-0}
sequences=("$@")
[ ${#sequences[@]} -gt 0 ] ||
  sequences=("$shared/rtabmap-samples/samples" /usr/share/doc/opencv-doc/examples/data/vtest.avi)
[ -x "$binbow" ] || { echo "timing.sh: no binbow at $binbow (build it, or set BINBOW)" >&2; exit 1; }
for s in "${sequences[@]}"; do
  [ -e "$s" ] || { echo "timing.sh: no sequence $s" >&2; exit 1; }
done

# shellcheck source=setup.sh
source "$here/setup.sh"
dld_setup "$work" "$binbow"
driver=$work/build/driver/dld_run
mkdir -p "$work/timing"

# stats VALUES...: "min–max (median)" of seconds, and the median alone in $median.
stats() {
  printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END {
    m = NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
    if (v[1] == v[NR]) printf "%.2f s|%.4f\n", m, m
    else printf "%.2f–%.2f s (%.2f)|%.4f\n", v[1], v[NR], m, m }'
}

echo "### binbow / DLoopDetector @${PEER_COMMIT[dorian3d/DLoopDetector]:0:7}: loop detection end to end, ORB features included"
echo
peer_header "$binbow"
echo "- rounds: $reps; binbow and DLoopDetector one after the other, nice $nice_level"
echo
echo "| sequence | DLoopDetector | binbow \`--threads 1\` | ratio | binbow \`--threads 2\` | ratio | CPU: DLoopDetector / binbow 1 / 2 | loops (DLoopDetector / binbow) |"
echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
for sequence in "${sequences[@]}"; do
  name=$(basename "$sequence")
  [ "$name" = samples ] && name=rtabmap-samples
  frequency=1
  [ -d "$sequence" ] || frequency=10
  dld=() one=() two=() cpu_dld=0 cpu_one=0 cpu_two=0 loops_dld=0 loops_binbow=0
  for ((round = 0; round < reps; round++)); do
    log=$work/timing/$name.dld.log
    nice -n "$nice_level" "$driver" --descriptor orb --vocab "$work/orb_default.yml.gz" \
      --frequency $frequency --seed 0 -o "$work/timing/$name.dld.csv" "$sequence" 2>"$log" ||
      { echo "timing.sh: DLoopDetector's driver failed, see $log" >&2; exit 1; }
    wall=
    read -r wall cpu loops_dld < <(sed -n 's/^frame loop: \([0-9.]*\) s wall, \([0-9.]*\) s CPU, [0-9]* frames, \([0-9]*\) loops$/\1 \2 \3/p' "$log") || true
    [ -n "$wall" ] || { echo "timing.sh: DLoopDetector failed, see $log" >&2; exit 1; }
    dld+=("$wall") cpu_dld=$cpu
    for threads in 1 2; do
      log=$work/timing/$name.binbow$threads.log
      csv=$work/timing/$name.binbow$threads.csv
      /usr/bin/time -f 'cpu %U %S' nice -n "$nice_level" "$binbow" detect-loops --threads $threads \
        --descriptor orb --vocab "$repo/data/vocab/orb_default.bbw" -o "$csv" "$sequence" >/dev/null 2>"$log" ||
        { echo "timing.sh: binbow failed, see $log" >&2; exit 1; }
      wall=$(sed -n 's/^detecting loops: [0-9]* done in \([0-9.]*\)s$/\1/p' "$log")
      cpu=$(awk '/^cpu / { printf "%.2f", $2 + $3 }' "$log")
      [ -n "$wall" ] || { echo "timing.sh: binbow failed, see $log" >&2; exit 1; }
      if [ $threads = 1 ]; then one+=("$wall") cpu_one=$cpu; else two+=("$wall") cpu_two=$cpu; fi
      loops_binbow=$(grep -c -E '^[0-9]+,' "$csv" || true)
    done
  done
  IFS='|' read -r dld_text dld_median <<<"$(stats "${dld[@]}")"
  IFS='|' read -r one_text one_median <<<"$(stats "${one[@]}")"
  IFS='|' read -r two_text two_median <<<"$(stats "${two[@]}")"
  printf '| %s | %s | %s | **%.1fx** | %s | **%.1fx** | %.2f / %s / %s s | %s / %s |\n' "$name" \
    "$dld_text" "$one_text" "$(awk "BEGIN { print $dld_median / $one_median }")" "$two_text" \
    "$(awk "BEGIN { print $dld_median / $two_median }")" "$cpu_dld" "$cpu_one" "$cpu_two" "$loops_dld" "$loops_binbow"
done
echo
echo "binbow's CPU time is the whole process's (its vocabulary load included); DLoopDetector's the frame loop's."
echo "- finished: $(date -u '+%H:%M UTC'); load average: $(cut -d' ' -f1-3 /proc/loadavg)"
