#!/usr/bin/env bash
# The word counts docs/online-vocabulary.md quotes, made by the CLI on the
# bundled sample (data/samples/rtabmap/samples, 84 frames, default features):
# the live words after the 84 frames with the default options, and the words
# without purging for each new-word distance of the threshold table.
#
#   scripts/online_vocabulary_figures.sh [-b BUILD_DIR]
#
# Needs BUILD_DIR/bin/binbow (default: build). Prints `key: value` lines.
set -euo pipefail
cd "$(dirname "$0")/.."
build=build
while getopts "b:" option; do
  case $option in
    b) build=$OPTARG ;;
    *) echo "usage: $0 [-b BUILD_DIR]" >&2; exit 2 ;;
  esac
done
binbow=$build/bin/binbow
[[ -x $binbow ]] || { echo "$0: $binbow not found; build the binbow target first" >&2; exit 1; }
frames=data/samples/rtabmap/samples
[[ -d $frames ]] || { echo "$0: $frames is missing" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The word count of an online run: `--save-vocabulary` reports
# "online vocabulary: N words -> FILE" on stderr.
words() {
  "$binbow" detect-loops "$frames" --online-vocabulary --save-vocabulary "$work/v.bbw" \
    -o "$work/loops.csv" "$@" 2>&1 >/dev/null |
    sed -n 's/^online vocabulary: \([0-9]*\) words.*/\1/p'
}

echo "hamming_kernel: $("$binbow" info --system | sed -n 's/^hamming_kernel: //p')"
echo "frames: $(find "$frames" -maxdepth 1 -name '*.jpg' | wc -l)"
echo "live_words_default_options: $(words)"
for distance in 0.12 0.16 0.20 0.25 0.30; do
  echo "words_no_purging_new_word_distance_$distance: $(words --purge-after-images 0 \
    --new-word-distance "$distance")"
done
