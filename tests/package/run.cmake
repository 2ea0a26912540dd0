# Installs the build tree into a scratch prefix, then builds and runs separate
# consumer projects: one of binbow::core alone (find_package COMPONENTS core),
# one of binbow::vision exactly as the README shows, the same two sources
# built with nothing but the compiler and pkg-config, and one of
# binbow::dbow2 written as ORB-SLAM2 uses DBoW2, built as C++11 through
# find_package and through pkg-config.
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(output "${out}" PARENT_SCOPE)
endfunction()

run("installing binbow" ${CMAKE_COMMAND} --install ${BINBOW_BUILD_DIR} --prefix ${prefix})
set(vocabulary ${prefix}/share/binbow/vocab/orb_default.bbw)
set(sample ${prefix}/share/binbow/samples/rtabmap/samples)
foreach(path ${vocabulary} ${sample})
  if(NOT EXISTS ${path})
    message(FATAL_ERROR "the install did not put ${path} in place")
  endif()
endforeach()

set(core_expect "words: [0-9]+")
set(vision_expect "frames: 84, database entries: 84, loops: [1-9][0-9]*")
foreach(consumer core vision)
  set(build ${WORK_DIR}/${consumer}-cmake)
  run("configuring the ${consumer} consumer" ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR}/${consumer}
      -B ${build} -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
  run("building the ${consumer} consumer" ${CMAKE_COMMAND} --build ${build})
  run("running the ${consumer} consumer (CMake)" ${build}/consumer ${vocabulary} ${sample})
  if(NOT output MATCHES "${${consumer}_expect}")
    message(FATAL_ERROR "the ${consumer} consumer printed: ${output}")
  endif()
  message(STATUS "CMake ${consumer}: ${output}")
endforeach()

# binbow::dbow2: an ORB-SLAM text vocabulary made by the installed CLI, and
# DBoW2's own numbers to reproduce.
set(orbvoc ${WORK_DIR}/ORBvoc.txt)
run("converting the vocabulary for the dbow2 consumer" ${prefix}/bin/binbow convert ${vocabulary} ${orbvoc})
set(build ${WORK_DIR}/dbow2-cmake)
run("configuring the dbow2 consumer" ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR}/dbow2
    -B ${build} -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
run("building the dbow2 consumer" ${CMAKE_COMMAND} --build ${build})
run("running the dbow2 consumer" ${build}/consumer ${orbvoc} ${CONSUMER_SOURCE_DIR}/../compat/dbow2_golden.txt)
if(NOT output MATCHES "numbers equal to DBoW2's: [1-9][0-9]*, mismatches: 0")
  message(FATAL_ERROR "the dbow2 consumer printed: ${output}")
endif()
message(STATUS "CMake dbow2: ${output}")

# pkg-config: binbow (core) and binbow-vision.
set(ENV{PKG_CONFIG_PATH} ${prefix}/${LIBDIR}/pkgconfig)
foreach(consumer core vision)
  if(consumer STREQUAL "core")
    set(module binbow)
  else()
    set(module binbow-vision)
  endif()
  run("pkg-config ${module}" pkg-config --cflags --libs ${module})
  string(STRIP "${output}" flags)
  separate_arguments(flags UNIX_COMMAND "${flags}")
  set(program ${WORK_DIR}/${consumer}-pkgconfig)
  run("building the ${consumer} consumer with pkg-config" ${CXX} -std=c++17 -O1
      ${CONSUMER_SOURCE_DIR}/${consumer}/main.cpp -o ${program} ${flags})
  run("running the ${consumer} consumer (pkg-config)" ${program} ${vocabulary} ${sample})
  if(NOT output MATCHES "${${consumer}_expect}")
    message(FATAL_ERROR "the ${consumer} consumer built with pkg-config printed: ${output}")
  endif()
  message(STATUS "pkg-config ${consumer}: ${output}")
endforeach()

# pkg-config: binbow-dbow2, as C++11.
run("pkg-config binbow-dbow2" pkg-config --cflags --libs binbow-dbow2)
string(STRIP "${output}" flags)
separate_arguments(flags UNIX_COMMAND "${flags}")
set(program ${WORK_DIR}/dbow2-pkgconfig)
run("building the dbow2 consumer with pkg-config" ${CXX} -std=c++11 -O1
    -I${CONSUMER_SOURCE_DIR}/../compat ${CONSUMER_SOURCE_DIR}/dbow2/main.cpp -o ${program} ${flags})
run("running the dbow2 consumer (pkg-config)" ${program} ${orbvoc}
    ${CONSUMER_SOURCE_DIR}/../compat/dbow2_golden.txt)
if(NOT output MATCHES "numbers equal to DBoW2's: [1-9][0-9]*, mismatches: 0")
  message(FATAL_ERROR "the dbow2 consumer built with pkg-config printed: ${output}")
endif()
message(STATUS "pkg-config dbow2: ${output}")
