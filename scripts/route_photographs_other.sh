#!/usr/bin/env bash
# Prints photographs for `binbow make-route` from Debian 12 packages other than
# those of scripts/route_photographs.sh, one path per line, sorted: the route
# cases of scripts/make_cases.py. Read from /usr/share, never copied into
# binbow:
#   lxqt   lxqt-themes: the 11 photographs among LXQt's wallpapers
#          (/usr/share/lxqt/wallpapers; its License file: CC-BY-SA-3.0,
#          "Copyright 2022: LXQt Project Team"; the package's copyright:
#          LGPL-2.1+ for Files: *); the drawn and abstract ones are left out
#   mate   mate-backgrounds: the 12 nature photographs (GPL-2+, each
#          photograph's author in the package's copyright). NOTE: the bundled
#          vocabularies were trained on these (data/vocab/PROVENANCE.md); a
#          route through them is not a test on unseen images
# A missing package is an error naming it (scripts/install-deps.sh installs
# them).
#
#   scripts/route_photographs_other.sh [lxqt|mate]   (default: both)
set -euo pipefail

sources=("$@")
[ ${#sources[@]} -gt 0 ] || sources=(lxqt mate)

lxqt=(Butterfly-Kenneth-Wimer.jpg Valendas.png after-the-rain.jpg appleflower.png beam.png
  butterfly.png cloud.png drop.png flowers.png fog.jpg this-is-not-windows.jpg)
mate=(Aqua Blinds Dune FreshFlower Garden GreenMeadow LadyBird RainDrops Storm TwoWings Wood
  YellowFlower)

need() {  # package
  if ! dpkg -s "$1" >/dev/null 2>&1; then
    echo "route_photographs_other.sh: error: the Debian package $1 is not installed; the" \
      "route photographs come from it (apt-get install $1, or scripts/install-deps.sh)" >&2
    exit 1
  fi
}

missing() {
  echo "route_photographs_other.sh: error: $1 is missing; reinstall the package $2" >&2
  exit 1
}

{
  for source in "${sources[@]}"; do
    case $source in
      lxqt)
        need lxqt-themes
        for name in "${lxqt[@]}"; do
          f=/usr/share/lxqt/wallpapers/$name
          [ -f "$f" ] || missing "$f" lxqt-themes
          echo "$f"
        done
        ;;
      mate)
        need mate-backgrounds
        for name in "${mate[@]}"; do
          f=/usr/share/backgrounds/mate/nature/$name.jpg
          [ -f "$f" ] || missing "$f" mate-backgrounds
          echo "$f"
        done
        ;;
      *)
        echo "route_photographs_other.sh: error: unknown source $source (lxqt or mate)" >&2
        exit 2
        ;;
    esac
  done
} | LC_ALL=C sort
