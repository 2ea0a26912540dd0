#!/usr/bin/env bash
# binbow in a ROS 2-style colcon workspace: this checkout (as a clone in the
# workspace's src/ would be) and src/binbow_colcon_consumer
# (tests/package/colcon_consumer, a package.xml depending on binbow) are built
# by `colcon build`; the consumer then runs from the install space with the
# vocabulary binbow installed, and so does binbow's CLI; binbow's package.xml and
# ament index marker are installed for ROS 2's tools. colcon finds binbow
# at the checkout's own path, so that binbow compiles with the same paths and
# flags as a Release build of the checkout, whose objects a compiler cache
# then reuses.
# Usage: tests/package/colcon_workspace.sh [more cmake arguments for colcon]
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
fail() { echo "colcon_workspace.sh: error: $*" >&2; exit 1; }
command -v colcon >/dev/null 2>&1 ||
  fail "colcon is not installed (Debian: colcon python3-colcon-cmake python3-colcon-ros, see scripts/install-deps.sh)"

# colcon and rosdep read the version from package.xml; it must be VERSION's.
project_version=$(cat "$repo/VERSION")
package_version=$(sed -nE 's|^ *<version>([^<]+)</version>.*|\1|p' "$repo/package.xml")
[ -n "$project_version" ] || fail "no version in $repo/VERSION"
[ "$project_version" = "$package_version" ] ||
  fail "package.xml has version '$package_version' but VERSION has $project_version"

workspace=$(mktemp -d)
trap 'rm -rf "$workspace"' EXIT
mkdir "$workspace/src"
cp -r "$repo/tests/package/colcon_consumer" "$workspace/src/binbow_colcon_consumer"

# colcon passes the same arguments to every package; the consumer ignores binbow's.
cmake_args=(-DCMAKE_BUILD_TYPE=Release -DBINBOW_WARNINGS_AS_ERRORS=ON -DBINBOW_BUILD_TESTS=OFF
  -DBINBOW_BUILD_BENCH=OFF -DBINBOW_BUILD_PYTHON=OFF --no-warn-unused-cli)
if command -v ccache >/dev/null 2>&1; then
  cmake_args+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cd "$workspace"
colcon build --base-paths "$repo" src --event-handlers console_cohesion+ --parallel-workers 1 \
  --cmake-args "${cmake_args[@]}" "$@"

for package in binbow binbow_colcon_consumer; do
  [ -d "install/$package" ] || fail "colcon did not build and install the package $package"
done

# ROS 2's tools (ros2 pkg, ament_index_python) find packages by the ament
# index marker and read their manifest from share/<package>.
for file in share/ament_index/resource_index/packages/binbow share/binbow/package.xml; do
  [ -f "install/binbow/$file" ] || fail "binbow's install space has no $file"
done
cmp -s "$repo/package.xml" install/binbow/share/binbow/package.xml ||
  fail "the installed package.xml is not the checkout's"

# The install space as a ROS 2 user gets it (setup scripts are not -u clean).
set +u
# shellcheck disable=SC1091
source install/setup.bash
set -u
vocabulary=install/binbow/share/binbow/vocab/orb_default.bbw
output=$(binbow_colcon_consumer "$vocabulary")
echo "$output"
[[ "$output" =~ words:\ [1-9][0-9]* ]] || fail "the consumer printed: $output"
binbow --version | grep -q "^binbow $project_version" || fail "binbow --version from the install space failed"
echo "colcon_workspace.sh: binbow and a package using it build and run in a colcon workspace"
