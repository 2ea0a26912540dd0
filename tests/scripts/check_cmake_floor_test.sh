#!/usr/bin/env bash
# scripts/check_cmake_floor.sh finds uses of CMake newer than 3.16 (naming
# file:line), lets a use guarded by if(CMAKE_VERSION VERSION_GREATER_EQUAL ...)
# pass, checks the else() branch of such a guard, and passes a clean tree.
# Usage: check_cmake_floor_test.sh <path to check_cmake_floor.sh>
set -euo pipefail
checker=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "check_cmake_floor_test: FAIL: $*" >&2; exit 1; }

mkdir -p "$work/repo/tests" "$work/repo/.ci"
cat >"$work/repo/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.16)
project(fixture CXX)
# A comment may name cmake_path() freely.
if(CMAKE_VERSION VERSION_GREATER_EQUAL 3.18)
  gtest_discover_tests(t DISCOVERY_MODE PRE_TEST)
else()
  file(REAL_PATH x y)
endif()
CMAKE
cat >"$work/repo/tests/CMakeLists.txt" <<'CMAKE'
gtest_discover_tests(t DISCOVERY_MODE PRE_TEST)
cmake_path(GET x PARENT_PATH y)
find_package(Foo CONFIG REQUIRED GLOBAL)
add_library(x $<TARGET_RUNTIME_DLLS:y>)
CMAKE
printf '#!/bin/sh\nctest --test-dir build -j2\ncmake -S . -B b -DCMAKE_COMPILE_WARNING_AS_ERROR=ON\n' \
  >"$work/repo/.ci/run"

set +e
"$checker" "$work/repo" >"$work/out" 2>&1
rc=$?
set -e
cat "$work/out"
[ "$rc" -eq 1 ] || fail "expected exit 1 on a tree with new CMake features, got $rc"
for expected in "CMakeLists.txt:7: file(REAL_PATH" "tests/CMakeLists.txt:1: gtest_discover_tests(DISCOVERY_MODE)" \
  "tests/CMakeLists.txt:2: cmake_path()" "tests/CMakeLists.txt:3: find_package(GLOBAL)" \
  "tests/CMakeLists.txt:4: \$<TARGET_RUNTIME_DLLS>" ".ci/run:2: ctest --test-dir" \
  ".ci/run:3: CMAKE_COMPILE_WARNING_AS_ERROR"; do
  grep -qF "$expected" "$work/out" || fail "the checker did not report: $expected"
done
if grep -qE "^CMakeLists.txt:(1|3|5):" "$work/out"; then
  fail "the checker reported a line it must accept (cmake_minimum_required 3.16, a comment, a guarded use)"
fi

# The same tree without the offending files passes.
rm "$work/repo/tests/CMakeLists.txt" "$work/repo/.ci/run"
sed -i '/REAL_PATH/d' "$work/repo/CMakeLists.txt"
"$checker" "$work/repo" || fail "the checker rejected a tree with only 3.16 features"
echo "check_cmake_floor_test: ok"
