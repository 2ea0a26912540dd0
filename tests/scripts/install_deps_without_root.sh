#!/usr/bin/env bash
# scripts/install-deps.sh run by a normal user on a machine without sudo must
# say what to do and exit 1 (it used to die with "exec: sudo: not found").
set -euo pipefail
script=$1
tools=$(mktemp -d)
trap 'rm -rf "$tools"' EXIT
for tool in bash id env; do ln -s "$(command -v $tool)" "$tools/$tool"; done
# The checkout may sit in a folder the unprivileged user cannot enter.
cp "$script" "$tools/install-deps.sh"
chmod 755 "$tools" "$tools/install-deps.sh"
set +e
out=$(setpriv --reuid=65534 --regid=65534 --clear-groups env PATH="$tools" bash "$tools/install-deps.sh" 2>&1)
status=$?
set -e
echo "$out"
[ "$status" -eq 1 ] || { echo "FAIL: exit status $status, expected 1"; exit 1; }
grep -q "run this script as root" <<<"$out" || { echo "FAIL: no advice to run as root"; exit 1; }
grep -q "install sudo" <<<"$out" || { echo "FAIL: no advice to install sudo"; exit 1; }
echo "PASS"
