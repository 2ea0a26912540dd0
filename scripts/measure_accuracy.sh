#!/usr/bin/env bash
# Precision and recall of `binbow detect-loops` on rtabmap-samples (84 frames,
# 44 queries with a ground-truth loop) with every vocabulary the accuracy
# targets of docs/loop-detection.md name, for one parameter file. The
# ablation table of docs/loop-detection.md is made with it:
#
#   scripts/measure_accuracy.sh [-b BUILD_DIR] [-w WORK_DIR] [-p PARAMS] [-m] [VOCAB...]
#   scripts/measure_accuracy.sh -s [-b BUILD_DIR] [-w WORK_DIR] [-p PARAMS] [-m] [CASE...]
#   scripts/measure_accuracy.sh -c SEED [-b BUILD_DIR] [-w WORK_DIR] [-p PARAMS] [CASE...]
#
# -p PARAMS  a --params file for detect-loops (JSON or YAML); default: none,
#            the detector's defaults.
# -m         also list the frames of each run that missed their loop, with
#            their status (from the run record).
# VOCAB      any of orb_default brief_default brief_lite kimera orb_L5 orb_L6
#            (default: all). orb_L5 / orb_L6 are ORB k=10 L=5 / L=6
#            vocabularies trained here by `binbow build-vocab` (2000 ORB per
#            image, seed 1) on opencv-doc-samples + dbow2-demo-images, cached in
#            WORK_DIR (default: build/measure_accuracy).
# -s         the variation suite instead: rtabmap-samples re-encoded, degraded
#            and rescaled by scripts/make_variations.sh (made once in
#            WORK_DIR/variations; needs ffmpeg), one row per CASE (default:
#            all, `scripts/make_variations.sh -l` lists them) with the
#            bundled orb_default and brief_default vocabularies.
# -c SEED    the case suite of that seed instead: rtabmap-samples rotated,
#            cropped, tilted, distorted, blurred, occluded, vignetted, its
#            second visit re-timed or re-lit, and make-route routes, by
#            scripts/make_cases.py (made once in WORK_DIR/cases-SEED; needs
#            ffmpeg, python3-numpy and the packages of
#            scripts/route_photographs_other.sh), one row per CASE (default:
#            all, `scripts/make_cases.py --seed 1 --list` lists them): ORB then
#            BRIEF (bundled vocabularies), precision/recall (found/with-loop,
#            false), each case against its own ground_truth.txt; then every
#            false loop as `case descriptor query<->match inliers N`.
# The shared data is read from ../shared/data (or $BINBOW_SHARED_DATA).
set -euo pipefail
cd "$(dirname "$0")/.."
build=build
work=
params=
misses=0
suite=0
cases_seed=
while getopts "b:w:p:msc:" option; do
  case $option in
    b) build=$OPTARG ;;
    w) work=$OPTARG ;;
    p) params=$(realpath "$OPTARG") ;;
    m) misses=1 ;;
    s) suite=1 ;;
    c) cases_seed=$OPTARG ;;
    *) exit 2 ;;
  esac
done
shift $((OPTIND - 1))
binbow="$build/bin/binbow"
[ -x "$binbow" ] || { echo "build binbow first: $binbow is missing" >&2; exit 1; }
work=${work:-$build/measure_accuracy}
mkdir -p "$work"
shared=${BINBOW_SHARED_DATA:-../shared/data}
samples="$shared/rtabmap-samples/samples"
gt="$shared/rtabmap-samples/samples_GT.bmp"
[ -d "$samples" ] && [ -f "$gt" ] || { echo "missing $samples or $gt" >&2; exit 1; }

trained_vocabulary() {  # levels -> path
  local path="$work/orb_k10_L$1.bbw"
  if [ ! -f "$path" ]; then
    "$binbow" build-vocab --descriptor orb --branching 10 --levels "$1" --seed 1 \
      --features-per-image 2000 -o "$path" "$shared/opencv-doc-samples" \
      "$shared/dbow2-demo-images" >/dev/null 2>&1
  fi
  echo "$path"
}

# measure LABEL DESCRIPTOR VOCABULARY IMAGES: one row.
measure() {
  local label=$1 descriptor=$2 vocab=$3 images=$4 name result
  name=$(tr -c 'A-Za-z0-9.\n' '_' <<<"$label")
  loops="$work/$name.csv"
  local rate=()  # a video's frames are the images, one per second
  [[ $images == *.mp4 ]] && rate=(--frequency 1)
  "$binbow" detect-loops --descriptor "$descriptor" --vocab "$vocab" ${params:+--params "$params"} \
    "${rate[@]}" -o "$loops" "$images" >/dev/null 2>&1
  result=$("$binbow" evaluate --gt "$gt" "$loops")
  value() { sed -n "s/^$1: //p" <<<"$result"; }
  printf '%-44s %-9.3f %-9.3f %s/%s (%s)\n' "$label" "$(value precision)" "$(value recall)" \
    "$(value 'queries found')" "$(value 'queries with a loop')" "$(value 'false positives')"
  if [ $misses -eq 1 ]; then
    python3 - "$loops.run.json" "${gt%.bmp}_pairs.txt" "$loops" <<'EOF'
import csv, json, sys
run = json.load(open(sys.argv[1]))
same = set()  # 0-based (query, match) from the 1-based pair list
for line in open(sys.argv[2]):
    if line.strip() and not line.startswith("#"):
        q, m = map(int, line.split()[:2])
        same |= {(q - 1, m - 1), (m - 1, q - 1)}
found = {int(r["query_index"]): int(r["match_index"]) for r in csv.DictReader(open(sys.argv[3]))}
for i, frame in enumerate(run["frames"]):
    if not any((i, j) in same for j in range(i)) or (i, found.get(i)) in same:
        continue
    wrong = f" FALSE match {found[i]}" if i in found else ""
    print(f"    miss {i}: {frame.get('status')} candidate {frame.get('match', '-')}"
          f" inliers {frame.get('inliers', '-')}{wrong}")
EOF
  fi
}

if [ -n "$cases_seed" ]; then
  [[ $cases_seed =~ ^[0-9]+$ ]] || { echo "-c takes a seed, a number" >&2; exit 2; }
  make_cases=(/usr/bin/python3 scripts/make_cases.py --seed "$cases_seed" --binbow "$binbow")
  cases=("$@")
  [ ${#cases[@]} -gt 0 ] || mapfile -t cases < <("${make_cases[@]}" --list | cut -d' ' -f1)
  out="$work/cases-$cases_seed"
  "${make_cases[@]}" "$samples" "${gt%.bmp}_pairs.txt" "$out" "${cases[@]}"
  false_loops=()
  printf '%-16s %-10s %-30s %s\n' case part "ORB p/r (found/loops, false)" \
    "BRIEF p/r (found/loops, false)"
  for name in "${cases[@]}"; do
    part=$("${make_cases[@]}" --list | awk -v name="$name" '$1 == name { print $2 }')
    images="$out/$name/frames"
    [ -d "$out/$name/route" ] && images="$out/$name/route/frames"
    row=()
    for descriptor in orb brief; do
      loops="$out/$name.$descriptor.csv"
      "$binbow" detect-loops --descriptor "$descriptor" \
        --vocab "data/vocab/${descriptor}_default.bbw" ${params:+--params "$params"} \
        -o "$loops" "$images" >/dev/null 2>&1
      result=$("$binbow" evaluate --gt "$out/$name/ground_truth.txt" "$loops" | tee "$loops.eval")
      value() { sed -n "s/^$1: //p" <<<"$result"; }
      row+=("$(printf '%.3f/%.3f (%s/%s, %s)' "$(value precision)" "$(value recall)" \
        "$(value 'queries found')" "$(value 'queries with a loop')" "$(value 'false positives')")")
      # evaluate counts the false loops; list them: detections that are no pair of the truth.
      while IFS= read -r line; do false_loops+=("$line"); done < <(python3 -c '
import csv, sys
same = set()
for line in open(sys.argv[2]):
    if line.strip() and not line.startswith("#"):
        q, m = map(int, line.split()[:2])
        same |= {(q, m), (m, q)}
for r in csv.DictReader(open(sys.argv[1])):
    q, m = int(r["query_index"]), int(r["match_index"])
    inliers = r["inliers"]
    if (q, m) not in same:
        print(f"{sys.argv[3]} {sys.argv[4]} {q}<->{m} inliers {inliers}")
' "$loops" "$out/$name/ground_truth.txt" "$name" "$descriptor")
    done
    printf '%-16s %-10s %-30s %s\n' "$name" "$part" "${row[0]}" "${row[1]}"
  done
  echo "false loops: ${#false_loops[@]}"
  for line in "${false_loops[@]}"; do echo "  $line"; done
  exit 0
fi

if [ $suite -eq 1 ]; then
  cases=("$@")
  [ ${#cases[@]} -gt 0 ] || mapfile -t cases < <(scripts/make_variations.sh -l | cut -d' ' -f1)
  scripts/make_variations.sh "$samples" "$work/variations" "${cases[@]}"
  printf '%-44s %-9s %-9s %s\n' "case (part) / descriptor" precision recall "found/loops (false)"
  for name in "${cases[@]}"; do
    part=$(scripts/make_variations.sh -l | awk -v name="$name" '$1 == name { print $2 }')
    images="$work/variations/$name"
    [ -f "$images/video.mp4" ] && images="$images/video.mp4"
    for descriptor in orb brief; do
      measure "$name ($part) $descriptor" "$descriptor" "data/vocab/${descriptor}_default.bbw" \
        "$images"
    done
  done
  exit 0
fi

vocabs=("$@")
[ ${#vocabs[@]} -gt 0 ] || vocabs=(orb_default brief_default brief_lite kimera orb_L5 orb_L6)
printf '%-44s %-9s %-9s %s\n' vocabulary precision recall "found/loops (false)"
for name in "${vocabs[@]}"; do
  case $name in
    orb_default) descriptor=orb vocab=data/vocab/orb_default.bbw ;;
    brief_default) descriptor=brief vocab=data/vocab/brief_default.bbw ;;
    brief_lite) descriptor=brief vocab=$shared/vins-lite-brief-vocab/brief_lite.voc.gz ;;
    kimera) descriptor=orb vocab=$shared/kimera-small-voc/small_voc.yml.gz ;;
    orb_L5) descriptor=orb vocab=$(trained_vocabulary 5) ;;
    orb_L6) descriptor=orb vocab=$(trained_vocabulary 6) ;;
    *) echo "unknown vocabulary $name" >&2; exit 2 ;;
  esac
  measure "$name" "$descriptor" "$vocab" "$samples"
done
