#!/usr/bin/env bash
# Prints the photographs `binbow make-route` walks through in the route
# accuracy test and docs/benchmarks.md, one path per line, sorted. They come
# from Debian 12 packages no bundled vocabulary was trained on
# (data/vocab/PROVENANCE.md), read from /usr/share, never copied into binbow:
#   lomiri-wallpapers-16.04, lomiri-wallpapers-20.04  photographs (CC-BY-4.0,
#       CC-BY-SA-3.0/4.0, CC0-1.0; the abstract ones are left out)
#   plasma-workspace-wallpapers  the photographs among KDE's wallpapers
#       (GPL-2+), each at its largest size only: the smaller files are the
#       same photographs, which would be other "places" showing the same scene
# A missing package is an error naming it (scripts/install-deps.sh installs
# them).
#
#   scripts/route_photographs.sh
set -euo pipefail

packages=(lomiri-wallpapers-16.04 lomiri-wallpapers-20.04 plasma-workspace-wallpapers)
for p in "${packages[@]}"; do
  if ! dpkg -s "$p" >/dev/null 2>&1; then
    echo "route_photographs.sh: error: the Debian package $p is not installed; the route" \
      "photographs come from it (apt-get install $p, or scripts/install-deps.sh)" >&2
    exit 1
  fi
done

backgrounds=/usr/share/backgrounds
wallpapers=/usr/share/wallpapers
lomiri=(Bridge_by_Sander_Klootwijk Dragonfly_by_Bolly Picture_0B_by_freespace
  Picture_1A_by_freespace Wine_by_Jakkub_Mede aitzgorri_by_Aitzol_Berasategi
  analogpattern_by_Peter_Nerlich free_by_Peter_Nerlich friends_by_Aitzol_Berasategi
  greentock_by_Peter_Nerlich life_by_Aitzol_Berasategi picosdeeuropa_by_Aitzol_Berasategi
  seeding_by_Clements_Engelhardt sunset_by_Aitzol_Berasategi Infinite-Sea_by_Aury88
  Kleiber_by_Lukas_Baubkus)
plasma=(BytheWater ColdRipple DarkestHour EveningGlow FallenLeaf Kite OneStandsOut Path
  summer_1am)

missing() {
  echo "route_photographs.sh: error: $1 is missing; reinstall the package $2" >&2
  exit 1
}

{
  for name in "${lomiri[@]}"; do
    f="$backgrounds/$name.jpg"
    [ -f "$f" ] || missing "$f" "lomiri-wallpapers-16.04 or lomiri-wallpapers-20.04"
    echo "$f"
  done
  for name in "${plasma[@]}"; do
    # Files are named WIDTHxHEIGHT.jpg: the one with the most pixels.
    f=$(find "$wallpapers/$name/contents/images" -maxdepth 1 -name '*x*.jpg' -printf '%f\n' \
      2>/dev/null | awk -Fx '{ split($2, h, "."); print $1 * h[1], $0 }' | sort -n | tail -1 |
      cut -d' ' -f2)
    [ -n "$f" ] || missing "$wallpapers/$name/contents/images" plasma-workspace-wallpapers
    echo "$wallpapers/$name/contents/images/$f"
  done
} | LC_ALL=C sort
