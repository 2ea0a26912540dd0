#!/usr/bin/env bash
# Prints the sorted list of training photographs shipped by Debian packages
# (installing the packages when missing), one path per line. The bundled
# default vocabularies are trained on it, the benchmark vocabulary on the
# --all list (every ViSP frame, ~1100 images); never on the evaluation
# sequence data/samples/rtabmap.
#
#   scripts/training_images.sh [--all]
set -euo pipefail
all=0
[ "${1:-}" = --all ] && all=1

packages=(opencv-doc mate-backgrounds visp-images-data)
missing=()
for p in "${packages[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" -ne 0 ]; then SUDO=sudo; else SUDO=; fi
  $SUDO apt-get update -qq >&2
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi

{
  # OpenCV's sample photographs (logos and drawings left out).
  find /usr/share/doc/opencv-doc/examples/data -maxdepth 1 -name '*.jpg' \
    ! -name '*Logo*' ! -name 'ellipses.jpg' ! -name 'pca_test1.jpg' ! -name 'HappyFish.jpg'
  # MATE's nature photographs.
  find /usr/share/backgrounds/mate/nature -name '*.jpg'
  visp=/usr/share/visp-images-data/ViSP-images
  images() { find "$@" -type f \( -name '*.pgm' -o -name '*.ppm' -o -name '*.png' -o -name '*.jpg' \); }
  if [ $all -eq 1 ]; then
    images "$visp"
  else
    # ViSP's camera frames: a castle model, a tracked cube (every 10th frame), AprilTag scenes.
    images "$visp/mbt-depth/castel/castel"
    images "$visp/mbt/cube" | LC_ALL=C sort | awk 'NR % 10 == 1'
    images "$visp/AprilTag/benchmark/640x480"
  fi
} | LC_ALL=C sort
