#!/usr/bin/env bash
# Checks that binbow builds with CMake 3.16 (Ubuntu 20.04) without needing that
# CMake: every CMake file of the repo is scanned for commands, keywords,
# variables, properties and generator expressions introduced in CMake 3.17 or
# later, and the shell scripts and docs for cmake/ctest command-line options
# introduced later. A use inside
#   if(CMAKE_VERSION VERSION_GREATER_EQUAL 3.x)
# is allowed (its else() branch is not). Prints file:line: what (version) for
# each finding and exits 1 if there is any.
# Usage: scripts/check_cmake_floor.sh [repo root]   (default: this script's repo)
set -euo pipefail
root=${1:-"$(cd "$(dirname "$0")/.." && pwd)"}
cd "$root"

# version<TAB>extended regular expression<TAB>what. From the "New in version"
# notes of the CMake 3.17 to 3.25 documentation (and a few later ones).
cmake_rules=$(cat <<'RULES'
3.17	cmake_minimum_required[[:space:]]*\([[:space:]]*VERSION[[:space:]]+3\.(1[7-9]|[2-9][0-9])	cmake_minimum_required above 3.16
3.17	cmake_minimum_required[[:space:]]*\([[:space:]]*VERSION[[:space:]]+[4-9]\.	cmake_minimum_required above 3.16
3.17	\bZIP_LISTS\b	foreach(ZIP_LISTS)
3.17	message[[:space:]]*\([[:space:]]*CHECK_(START|PASS|FAIL)\b	message(CHECK_*)
3.17	\bCMAKE_CURRENT_FUNCTION(_LIST_DIR|_LIST_FILE|_LIST_LINE)?\b	CMAKE_CURRENT_FUNCTION*
3.17	\bCMAKE_MESSAGE_CONTEXT\b	CMAKE_MESSAGE_CONTEXT
3.17	\bCMAKE_FIND_DEBUG_MODE\b	CMAKE_FIND_DEBUG_MODE
3.17	\bCMAKE_CUDA_RUNTIME_LIBRARY\b	CMAKE_CUDA_RUNTIME_LIBRARY
3.17	\bDEPRECATION[[:space:]]	DEPRECATION target property
3.17	-E[[:space:]]+rm\b	cmake -E rm
3.18	\bcmake_language[[:space:]]*\(	cmake_language()
3.18	file[[:space:]]*\([[:space:]]*(CONFIGURE|ARCHIVE_CREATE|ARCHIVE_EXTRACT)\b	file(CONFIGURE/ARCHIVE_*)
3.18	\bECHO_(OUTPUT|ERROR)_VARIABLE\b	execute_process(ECHO_*_VARIABLE)
3.18	\bDISCOVERY_MODE\b	gtest_discover_tests(DISCOVERY_MODE)
3.18	\bDevelopment\.(Module|Embed)\b	FindPython Development.Module/Embed
3.18	find_(program|library|file|path)[[:space:]]*\([^)]*[[:space:]]REQUIRED\b	find_*(REQUIRED)
3.18	\bCOMPARE[[:space:]]+NATURAL\b	list(SORT COMPARE NATURAL)
3.18	\b(TARGET_DIRECTORY)\b	set/get_property(TARGET_DIRECTORY)
3.18	\bUNITY_BUILD_MODE\b	UNITY_BUILD_MODE
3.18	\bCUDA_ARCHITECTURES\b	CUDA_ARCHITECTURES
3.18	\$<(LINK_LANGUAGE|LINK_LANG_AND_ID|DEVICE_LINK|HOST_LINK)\b	$<LINK_LANGUAGE...> genex family
3.18	-E[[:space:]]+cat\b	cmake -E cat
3.18	\bCheckLinkerFlag\b|\bcheck_linker_flag\b	CheckLinkerFlag
3.19	file[[:space:]]*\([[:space:]]*(REAL_PATH|CHMOD|CHMOD_RECURSE)\b	file(REAL_PATH/CHMOD)
3.19	string[[:space:]]*\([[:space:]]*JSON\b	string(JSON)
3.19	\bCOMMAND_ERROR_IS_FATAL\b	execute_process(COMMAND_ERROR_IS_FATAL)
3.19	\bNO_SOURCE_PERMISSIONS\b	configure_file(NO_SOURCE_PERMISSIONS)
3.19	\bOPTIMIZE_DEPENDENCIES\b	OPTIMIZE_DEPENDENCIES
3.19	\$<CONFIG:[^>]*,	$<CONFIG:a,b>
3.19	-E[[:space:]]+create_hardlink\b	cmake -E create_hardlink
3.19	\bCheck(Compiler|Source)(Flag|Compiles|Runs)\b|\bcheck_(compiler_flag|source_compiles|source_runs)\b	Check{CompilerFlag,SourceCompiles,SourceRuns}
3.19	find_package[[:space:]]*\([^)]*[0-9]\.\.\.[0-9]	find_package version range
3.20	\bcmake_path[[:space:]]*\(	cmake_path()
3.20	\$<(OUTPUT_CONFIG|COMMAND_CONFIG)\b	$<OUTPUT_CONFIG>/$<COMMAND_CONFIG>
3.20	\bUSE_SOURCE_PERMISSIONS\b	configure_file(USE_SOURCE_PERMISSIONS)
3.20	\bcxx_std_23\b	cxx_std_23
3.20	\bCMAKE_DEPENDS_USE_COMPILER\b	CMAKE_DEPENDS_USE_COMPILER
3.20	\bNEWLINE_STYLE\b.*\bGENERATE\b|\bGENERATE\b.*\bNEWLINE_STYLE\b	file(GENERATE NEWLINE_STYLE)
3.21	\$<TARGET_RUNTIME_DLLS\b	$<TARGET_RUNTIME_DLLS>
3.21	file[[:space:]]*\([[:space:]]*COPY_FILE\b	file(COPY_FILE)
3.21	\b(RUNTIME_DEPENDENCY_SET|IMPORTED_RUNTIME_ARTIFACTS)\b	install(RUNTIME_DEPENDENCY_SET/IMPORTED_RUNTIME_ARTIFACTS)
3.21	\bALL_COMPONENTS\b	install(SCRIPT/CODE ALL_COMPONENTS)
3.21	\b(PROJECT_IS_TOP_LEVEL|[A-Za-z0-9_]+_IS_TOP_LEVEL)\b	PROJECT_IS_TOP_LEVEL
3.21	\bNO_CACHE\b	find_*(NO_CACHE)
3.21	\b(CMAKE_)?[A-Z]+_LINKER_LAUNCHER\b	<LANG>_LINKER_LAUNCHER
3.22	\bENVIRONMENT_MODIFICATION\b	ENVIRONMENT_MODIFICATION test property
3.22	\bCMAKE_INSTALL_MODE\b	CMAKE_INSTALL_MODE
3.22	\bCMAKE_REQUIRE_FIND_PACKAGE_	CMAKE_REQUIRE_FIND_PACKAGE_<Pkg>
3.23	\bFILE_SET\b	target_sources/install(FILE_SET)
3.23	\b(HEADER_SETS|HEADER_SET|INTERFACE_HEADER_SETS|IMPORTED_NO_SYSTEM)\b	header sets, IMPORTED_NO_SYSTEM
3.23	\bINITIALIZE_FROM_VARIABLE\b	define_property(INITIALIZE_FROM_VARIABLE)
3.24	\b(CMAKE_)?COMPILE_WARNING_AS_ERROR\b	COMPILE_WARNING_AS_ERROR
3.24	find_package[[:space:]]*\([^)]*[[:space:]]GLOBAL\b	find_package(GLOBAL)
3.24	\bCMAKE_FIND_PACKAGE_TARGETS_GLOBAL\b	CMAKE_FIND_PACKAGE_TARGETS_GLOBAL
3.24	\$<(LINK_LIBRARY|LINK_GROUP|PATH|PATH_EQUAL):	$<LINK_LIBRARY>/$<LINK_GROUP>/$<PATH>
3.24	\bPATH_EQUAL\b	if(PATH_EQUAL)
3.24	\b(OVERRIDE_FIND_PACKAGE|FIND_PACKAGE_ARGS|SET_DEPENDENCY_PROVIDER)\b	FetchContent/dependency providers
3.24	\b(CMAKE_COLOR_DIAGNOSTICS|CMAKE_FIND_PACKAGE_REDIRECTS_DIR|CMAKE_VERIFY_INTERFACE_HEADER_SETS|VERIFY_INTERFACE_HEADER_SETS|INTERFACE_LINK_LIBRARIES_DIRECT|LINK_LIBRARY_OVERRIDE)\b	3.24 variable/property
3.25	^[[:space:]]*(block|endblock)[[:space:]]*\(	block()/endblock()
3.25	return[[:space:]]*\([[:space:]]*PROPAGATE\b	return(PROPAGATE)
3.25	add_subdirectory[[:space:]]*\([^)]*[[:space:]]SYSTEM\b	add_subdirectory(SYSTEM)
3.25	\b(EXPORT_NO_SYSTEM|CMAKE_MSVC_DEBUG_INFORMATION_FORMAT|VALIDATOR)\b	3.25 keyword/variable
3.25	\bcxx_std_26\b	cxx_std_26
3.25	\b(LINUX|BSD)\b[[:space:]]*\)	LINUX/BSD variables
3.26	\$<BUILD_LOCAL_INTERFACE\b	$<BUILD_LOCAL_INTERFACE>
3.26	-E[[:space:]]+copy_directory_if_different\b	cmake -E copy_directory_if_different
3.27	\$<(LIST|COMPILE_ONLY|TARGET_RUNTIME_DLL_DIRS):	3.27 generator expression
RULES
)

# cmake/ctest command-line options, in scripts and in the commands the docs show.
cli_rules=$(cat <<'RULES'
3.20	ctest[^|;&]*[[:space:]]--test-dir\b	ctest --test-dir
3.17	ctest[^|;&]*[[:space:]]--(no-tests|repeat)\b	ctest --no-tests/--repeat
3.18	ctest[^|;&]*[[:space:]]--stop-on-failure\b	ctest --stop-on-failure
3.21	ctest[^|;&]*[[:space:]]--output-junit\b	ctest --output-junit
3.21	cmake[^|;&]*[[:space:]]--(toolchain|install-prefix)\b	cmake --toolchain/--install-prefix
3.19	cmake[^|;&]*[[:space:]]--(preset|list-presets)\b	cmake --preset
3.24	cmake[^|;&]*[[:space:]]--(fresh|compile-no-warning-as-error)\b	cmake --fresh/--compile-no-warning-as-error
3.24	-DCMAKE_COMPILE_WARNING_AS_ERROR\b	CMAKE_COMPILE_WARNING_AS_ERROR
3.17	cmake[[:space:]]+-E[[:space:]]+rm\b	cmake -E rm
3.18	cmake[[:space:]]+-E[[:space:]]+cat\b	cmake -E cat
RULES
)

# This checker and its test spell out the options they look for.
prune=(-path ./.git -o -path './build*' -o -path '*/_deps' -o -path ./.pytest_cache
  -o -path ./scripts/check_cmake_floor.sh -o -path ./tests/scripts/check_cmake_floor_test.sh)
mapfile -t cmake_files < <(find . \( "${prune[@]}" \) -prune -o -type f \
  \( -name CMakeLists.txt -o -name '*.cmake' -o -name '*.cmake.in' \) -print | sort)
mapfile -t cli_files < <(find . \( "${prune[@]}" \) -prune -o -type f \
  \( -name '*.sh' -o -name '*.md' -o -name '*.py' -o -path ./.ci/run \) -print | sort)
if [ "${#cmake_files[@]}" -eq 0 ]; then
  echo "check_cmake_floor.sh: error: no CMake files under $root" >&2
  exit 1
fi

# awk: comments are dropped; lines inside if(CMAKE_VERSION VERSION_GREATER[_EQUAL] 3.x)
# with x >= 17 are skipped (the if's else()/elseif() branches are checked).
# \b (word boundary) is written for readability above; awk has none, so it
# becomes "not a name character" on its side.
scan() {
  local rules
  rules=$(sed -E -e 's/\\b([A-Za-z_(])/(^|[^A-Za-z0-9_])\1/g' \
    -e 's/([A-Za-z0-9_)])\\b/\1([^A-Za-z0-9_]|$)/g' <<<"$1")
  shift
  RULES=$rules awk '
    BEGIN {
      n = split(ENVIRON["RULES"], lines, "\n")
      for (i = 1; i <= n; i++) {
        if (lines[i] == "") continue
        split(lines[i], f, "\t")
        count++; version[count] = f[1]; pattern[count] = f[2]; what[count] = f[3]
      }
    }
    FNR == 1 { depth = 0; guarded = 0 }
    {
      line = $0
      sub(/(^|[[:space:]])#.*$/, "", line)
      if (FILENAME ~ /(\.cmake|CMakeLists\.txt|\.cmake\.in)$/) {
        if (line ~ /^[[:space:]]*if[[:space:]]*\(/) {
          depth++
          guard[depth] = (line ~ /CMAKE_VERSION[[:space:]]+VERSION_GREATER(_EQUAL)?[[:space:]]+3\.(1[7-9]|[2-9][0-9])/)
          if (guard[depth]) guarded++
          next
        }
        if (line ~ /^[[:space:]]*(else|elseif)[[:space:]]*\(/ && depth > 0 && guard[depth]) {
          guard[depth] = 0; guarded--
        }
        if (line ~ /^[[:space:]]*endif[[:space:]]*\(/ && depth > 0) {
          if (guard[depth]) guarded--
          depth--
          next
        }
        if (guarded > 0) next
      }
      for (i = 1; i <= count; i++)
        if (line ~ pattern[i]) {
          printf "%s:%d: %s needs CMake %s\n", substr(FILENAME, 3), FNR, what[i], version[i]
          found = 1
        }
    }
    END { exit found }' "$@"
}

status=0
scan "$cmake_rules" "${cmake_files[@]}" || status=1
if [ "${#cli_files[@]}" -gt 0 ]; then
  scan "$cli_rules" "${cli_files[@]}" || status=1
fi
if [ "$status" -ne 0 ]; then
  echo "check_cmake_floor.sh: error: the uses above need a CMake newer than 3.16, the oldest" \
    "binbow supports; guard them with if(CMAKE_VERSION VERSION_GREATER_EQUAL 3.x) or do without" >&2
  exit 1
fi
echo "check_cmake_floor.sh: ${#cmake_files[@]} CMake files and ${#cli_files[@]} scripts and docs need no CMake newer than 3.16"
