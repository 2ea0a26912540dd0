#!/usr/bin/env bash
# Rebuilds the bundled default vocabularies in data/vocab/ from real
# photographs shipped by Debian packages (never from the evaluation sequence
# data/samples/rtabmap). Deterministic: fixed seeds, a sorted image list, so
# re-running it reproduces the committed files byte for byte.
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

packages=(opencv-doc mate-backgrounds visp-images-data)
missing=()
for p in "${packages[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" -ne 0 ]; then SUDO=sudo; else SUDO=; fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

list=$(mktemp --suffix=.txt)
trap 'rm -f "$list"' EXIT
{
  # OpenCV's sample photographs (logos and drawings left out).
  find /usr/share/doc/opencv-doc/examples/data -maxdepth 1 -name '*.jpg' \
    ! -name '*Logo*' ! -name 'ellipses.jpg' ! -name 'pca_test1.jpg' ! -name 'HappyFish.jpg'
  # MATE's nature photographs.
  find /usr/share/backgrounds/mate/nature -name '*.jpg'
  # ViSP's camera frames: a castle model, a tracked cube (every 10th frame), AprilTag scenes.
  visp=/usr/share/visp-images-data/ViSP-images
  images() { find "$@" -type f \( -name '*.pgm' -o -name '*.ppm' -o -name '*.png' -o -name '*.jpg' \); }
  images "$visp/mbt-depth/castel/castel"
  images "$visp/mbt/cube" | LC_ALL=C sort | awk 'NR % 10 == 1'
  images "$visp/AprilTag/benchmark/640x480"
} | LC_ALL=C sort > "$list"
echo "$(wc -l < "$list") training images" >&2

mkdir -p "$out"
# k=10, L=4: the training set (~250k descriptors) fills ~10k words with ~25
# descriptors each; deeper trees leave one or two per word (see PROVENANCE.md).
for descriptor in orb brief; do
  "$binbow" build-vocab --descriptor "$descriptor" --branching 10 --levels 4 --seed 1 \
    --features-per-image 2000 --max-width 640 -o "$out/${descriptor}_default.bbw" "$list"
done
