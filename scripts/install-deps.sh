#!/usr/bin/env bash
# Installs everything binbow needs to build, test and benchmark on Debian 12
# (other releases: docs/install.md).
# Run as root (or through sudo). Only Debian packages; nothing is downloaded
# at build time.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config git ccache
  libopencv-dev libjpeg-dev libmatio-dev zlib1g-dev ffmpeg
  libgtest-dev libgmock-dev libboost-dev libbenchmark-dev
  libboost-serialization-dev
  opencv-doc
  libcli11-dev nlohmann-json3-dev
  pybind11-dev python3-dev python3-numpy
  python3-pytest python3-opencv python3-matplotlib python3-pip python3-setuptools python3-wheel
  python3-distributed
  clang libclang-rt-14-dev clang-format strace
  chromium
  lomiri-wallpapers-16.04 lomiri-wallpapers-20.04 plasma-workspace-wallpapers
  lxqt-themes mate-backgrounds
  colcon python3-colcon-cmake python3-colcon-ros python3-colcon-bash python3-colcon-recursive-crawl
  python3-colcon-parallel-executor python3-colcon-package-selection python3-colcon-output
  python3-colcon-library-path python3-colcon-metadata python3-colcon-defaults
)
# On x86-64, the aarch64 cross build tested under emulation
# (scripts/test-aarch64.sh): the cross compiler, qemu, and the target's
# libraries through multiarch. An arm64 machine builds natively instead.
cross_arm64=false
if [ "$(dpkg --print-architecture)" = amd64 ]; then
  cross_arm64=true
  packages+=(g++-aarch64-linux-gnu qemu-user
    zlib1g-dev:arm64 libopencv-core-dev:arm64 libgtest-dev:arm64 libgmock-dev:arm64)
fi
if [ "$(id -u)" -ne 0 ]; then
  if ! command -v sudo >/dev/null 2>&1; then
    echo "install-deps.sh: error: installing packages needs root: run this script as root," \
      "or install sudo, or install these Debian packages yourself: ${packages[*]}" >&2
    exit 1
  fi
  exec sudo "$0" "$@"
fi
export DEBIAN_FRONTEND=noninteractive
# arm64 packages beside the build machine's (multiarch), for the cross build.
if $cross_arm64; then dpkg --add-architecture arm64; fi
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null
echo "binbow dependencies installed."
