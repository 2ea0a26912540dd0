#!/usr/bin/env bash
# Cross-compiles binbow for aarch64 with Debian's g++-aarch64-linux-gnu and
# arm64 packages (cmake/toolchains/aarch64-linux-gnu.cmake; scripts/install-deps.sh
# installs them) and runs under qemu-aarch64, with the NEON kernel:
#  - the core, formats, database and DBoW2 compat tests (the kernel tests with
#    the portable kernel as well);
#  - the CLI's commands that read no image (info, convert, db remove);
#  - the files written under qemu (every vocabulary format, databases, the
#    CLI's outputs) compared byte for byte with those written natively.
# binbow::vision and the image commands are not cross-built: Debian's arm64
# OpenCV with all its modules would bring hundreds of packages.
# Usage: scripts/test-aarch64.sh [NATIVE_BUILD]
# NATIVE_BUILD (default: build) is a native build with binbow and test_formats
# built, for the comparison; the cross build goes to $BINBOW_AARCH64_BUILD
# (default: build-aarch64), through ccache when it is installed.
set -euo pipefail
cd "$(dirname "$0")/.."
native=${1:-build}
cross=${BINBOW_AARCH64_BUILD:-build-aarch64}

for tool in aarch64-linux-gnu-g++ qemu-aarch64; do
  if ! command -v "$tool" >/dev/null; then
    echo "test-aarch64.sh: error: $tool not found: run scripts/install-deps.sh" \
      "(Debian: g++-aarch64-linux-gnu qemu-user, and arm64 packages through multiarch)" >&2
    exit 1
  fi
done
for program in binbow test_formats; do
  if [ ! -x "$native/bin/$program" ]; then
    echo "test-aarch64.sh: error: $native/bin/$program not found: build it natively first" \
      "(cmake -S . -B $native -G Ninja && cmake --build $native --target binbow test_formats)," \
      "or give the native build's folder as the argument" >&2
    exit 1
  fi
done

launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
cmake -S . -B "$cross" -G Ninja --no-warn-unused-cli -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/aarch64-linux-gnu.cmake -DBINBOW_BUILD_VISION=OFF \
  -DBINBOW_WARNINGS_AS_ERRORS=ON "${launcher[@]}"
cmake --build "$cross" -j"$(nproc)" --target binbow test_core test_formats test_database test_compat

# The arm64 loader and libraries are found where multiarch installs them.
# The kernel is NEON unless arm_kernel says otherwise.
arm() { BINBOW_HAMMING_KERNEL=${arm_kernel:-neon} qemu-aarch64 "$@"; }
fail() {
  echo "test-aarch64.sh: FAIL: $*" >&2
  exit 1
}

echo "=== binbow info --system under qemu-aarch64"
system=$(arm "$cross/bin/binbow" info --system)
echo "$system"
grep -qx "hamming_kernels_supported: generic neon" <<<"$system" || fail "kernels supported"
grep -qx "hamming_kernel: neon" <<<"$system" || fail "kernel in use"
if arm_kernel=avx2 arm "$cross/bin/binbow" info --system >/dev/null 2>&1; then
  fail "BINBOW_HAMMING_KERNEL=avx2 was accepted on aarch64"
fi

echo "=== tests under qemu-aarch64, NEON kernel"
for area in core formats compat; do
  echo "--- test_$area"
  arm "$cross/bin/test_$area" --gtest_brief=1
done
# The database suites that depend on the processor: files (bytes, mapping,
# the forward index's packing) and scores. Under emulation the whole suite
# takes six minutes, more than this stage's budget: not the suites of
# processor-independent logic (Database, query modes, journals, counts: three
# minutes) nor the concurrent ones (qemu runs aarch64's weakly ordered memory
# with x86-64's strong ordering, so threads prove nothing more here than
# natively), and not two file tests that repeat on 65,536 ids what the others
# check on fewer (18 s each). The PortableBytes test and the comparison below
# check the databases' bytes.
echo "--- test_database"
arm "$cross/bin/test_database" --gtest_brief=1 --gtest_filter="$(printf '%s:' \
  'DatabaseFile.*' 'DatabaseAppendJournal.*' 'ForwardIndex.*' 'PackedFeatureVector.*' \
  'AllScorings/*')-$(printf '%s:' \
  DatabaseFile.SaveStreamsTheBytesSerializeReturns DatabaseFile.PartsOf65536IdsRoundTrip)"
echo "--- test_core's kernel tests with the portable kernel"
arm_kernel=generic arm "$cross/bin/test_core" --gtest_brief=1 \
  --gtest_filter='Kernel*:Hamming*:Vocabulary*'

echo "=== the same bytes written under qemu-aarch64 as natively"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
BINBOW_PORTABLE_BYTES_DIR="$work/x86_64" "$native/bin/test_formats" --gtest_brief=1 \
  --gtest_filter='PortableBytes.*'
BINBOW_PORTABLE_BYTES_DIR="$work/aarch64" arm "$cross/bin/test_formats" --gtest_brief=1 \
  --gtest_filter='PortableBytes.*'
# The CLI on each side: vocabularies converted to every format, a database
# whose entries are removed and compacted, and what info prints.
for side in x86_64 aarch64; do
  if [ "$side" = x86_64 ]; then cli=("$native/bin/binbow"); else cli=(arm "$cross/bin/binbow"); fi
  out="$work/$side"
  for format in yml.gz txt bin dbow3 fbow vins.bin; do
    "${cli[@]}" convert data/vocab/orb_default.bbw "$out/orb_default.$format" >/dev/null
  done
  "${cli[@]}" convert "$out/orb_default.txt" "$out/orb_default-from-txt.bbw" >/dev/null
  cp "$out/database.bbdb" "$out/database-removed.bbdb"
  "${cli[@]}" db remove "$out/database-removed.bbdb" 3 7 --compact >/dev/null
  for file in data/vocab/brief_default.bbw "$out/database-removed.bbdb" "$out/vocabulary.yml"; do
    "${cli[@]}" info "$file" | sed "s|$out|OUT|g"
  done >"$out/info.txt"
done
# A lock file holds its writer's process id.
rm -f "$work"/*/*.lock
compared=0
for file in "$work"/x86_64/*; do
  name=$(basename "$file")
  cmp "$file" "$work/aarch64/$name" || fail "$name differs between x86-64 and aarch64"
  compared=$((compared + 1))
done
[ "$compared" -ge 19 ] || fail "only $compared files compared, 19 expected"
echo "$compared files identical on x86-64 and aarch64"
echo "test-aarch64.sh: all passed"
