#!/usr/bin/env bash
# Rebuilds the bundled default vocabularies in data/vocab/ from real
# photographs shipped by Debian packages (scripts/training_images.sh; never
# from the evaluation sequence data/samples/rtabmap). Deterministic: fixed
# seeds, a sorted image list, so re-running it reproduces the committed files
# byte for byte.
#
#   scripts/make_default_vocabularies.sh [BUILD_DIR] [OUT_DIR]
#
# BUILD_DIR: where bin/binbow is (default: build); OUT_DIR: data/vocab.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out=${2:-data/vocab}
binbow="$build/bin/binbow"
[ -x "$binbow" ] || { echo "build binbow first: $binbow is missing" >&2; exit 1; }

list=$(mktemp --suffix=.txt)
trap 'rm -f "$list"' EXIT
scripts/training_images.sh > "$list"
echo "$(wc -l < "$list") training images" >&2

mkdir -p "$out"
# k=10, L=4: the training set (~250k descriptors) fills ~10k words with ~25
# descriptors each; deeper trees leave one or two per word (see PROVENANCE.md).
for descriptor in orb brief; do
  "$binbow" build-vocab --descriptor "$descriptor" --branching 10 --levels 4 --seed 1 \
    --features-per-image 2000 --max-width 640 -o "$out/${descriptor}_default.bbw" "$list"
done
