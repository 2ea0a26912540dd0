#!/usr/bin/env bash
# Rebuilds the default vocabularies into a temporary directory and checks that
# they are byte-identical to the committed data/vocab files.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
scripts/make_default_vocabularies.sh "$build" "$tmp" >/dev/null 2>&1
for f in orb_default.bbw brief_default.bbw; do
  cmp "data/vocab/$f" "$tmp/$f" || { echo "data/vocab/$f differs from a fresh build" >&2; exit 1; }
done
echo "default vocabularies reproduced byte for byte"
