# With the build tree installed in the scratch prefix PREFIX (install.cmake),
# checks the files for other tools (ROS 2's manifest and index marker, the
# pkg-config files, parsed strictly), runs the installed CLI, then builds and
# runs separate consumer projects: one of binbow::core alone
# (find_package COMPONENTS core), one of binbow::vision exactly as the README
# shows, the same two sources built with nothing but the compiler and
# pkg-config, and one of binbow::dbow2 written as ORB-SLAM2 uses DBoW2, built
# as C++11 through find_package and through pkg-config, the programs of
# binbow::dbow2_names written as DLoopDetector and ORB-SLAM2/3 call DBoW2
# (their include lines unchanged), the same two ways, and one written as
# VINS uses its copy of DBoW2, as C++14 (needs Boost and OpenCV imgproc).
# With SHARED, every
# program must link binbow's shared libraries.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(prefix ${PREFIX})
include(${CMAKE_CURRENT_LIST_DIR}/check_pc_files.cmake)

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(output "${out}" PARENT_SCOPE)
endfunction()

# A program links libbinbow_<library>.so.<soversion> exactly when the build is shared.
function(expect_linkage program library)
  run("reading the dynamic section of ${program}" readelf -d ${program})
  string(REGEX MATCH "NEEDED[^\n]*\\[libbinbow_${library}\\.so\\.[0-9]" needed "${output}")
  if(SHARED AND NOT needed)
    message(FATAL_ERROR "${program} does not link libbinbow_${library}.so in a shared build:\n${output}")
  elseif(NOT SHARED AND needed)
    message(FATAL_ERROR "${program} links libbinbow_${library}.so in a static build:\n${output}")
  endif()
endfunction()

# ROS 2's tools find an installed package by its ament index marker, and read
# its manifest in share/<package>.
foreach(file ${DATADIR}/ament_index/resource_index/packages/binbow ${DATADIR}/binbow/package.xml)
  if(NOT EXISTS ${prefix}/${file})
    message(FATAL_ERROR "the install did not put ${file} in the prefix")
  endif()
endforeach()
file(READ ${SOURCE_DIR}/package.xml source_manifest)
file(READ ${prefix}/${DATADIR}/binbow/package.xml installed_manifest)
if(NOT installed_manifest STREQUAL source_manifest)
  message(FATAL_ERROR "the installed package.xml is not the source's")
endif()

# The pkg-config files as installed: strictly parsed, and validated by
# pkg-config itself where it can (pkgconf's --validate).
file(GLOB pc_files ${prefix}/${LIBDIR}/pkgconfig/*.pc)
list(LENGTH pc_files pc_count)
if(NOT pc_count EQUAL 4)
  message(FATAL_ERROR "expected binbow.pc, binbow-vision.pc, binbow-dbow2.pc and binbow-dbow2-names.pc installed: ${pc_files}")
endif()
binbow_check_pc_files("${pc_files}")
set(ENV{PKG_CONFIG_PATH} ${prefix}/${LIBDIR}/pkgconfig)
execute_process(COMMAND pkg-config --help OUTPUT_VARIABLE help ERROR_VARIABLE help)
if(help MATCHES "--validate")
  foreach(pc_file ${pc_files})
    run("pkg-config --validate ${pc_file}" pkg-config --validate ${pc_file})
  endforeach()
else()
  message(STATUS "pkg-config has no --validate: the strict parse alone checked the .pc files")
endif()

set(vocabulary ${prefix}/share/binbow/vocab/orb_default.bbw)
set(sample ${prefix}/share/binbow/samples/rtabmap/samples)
foreach(path ${vocabulary} ${sample})
  if(NOT EXISTS ${path})
    message(FATAL_ERROR "the install did not put ${path} in place")
  endif()
endforeach()

# The installed CLI runs from the prefix (shared: through its install RPATH).
set(cli ${prefix}/${BINDIR}/binbow)
run("running the installed binbow --version" ${cli} --version)
if(NOT output MATCHES "^binbow [0-9]+\\.[0-9]+\\.[0-9]+")
  message(FATAL_ERROR "the installed binbow --version printed: ${output}")
endif()
run("running the installed binbow info" ${cli} info ${vocabulary})
if(NOT output MATCHES "words")
  message(FATAL_ERROR "the installed binbow info printed: ${output}")
endif()
expect_linkage(${cli} core)
# The commands that read images are a module beside binbow_media, loaded
# from the prefix (shared: linking the installed libbinbow_vision.so).
set(vision_commands ${prefix}/${LIBDIR}/binbow/binbow_cli_vision.so)
run("running the installed binbow features" ${cli} features ${sample}/1.jpg)
if(NOT output MATCHES "keypoints")
  message(FATAL_ERROR "the installed binbow features printed: ${output}")
endif()
expect_linkage(${vision_commands} vision)

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
  expect_linkage(${build}/consumer ${consumer})
  message(STATUS "CMake ${consumer}: ${output}")
endforeach()

# The DBoW2 layer's consumers below are built without optimisation (no build
# type, -O0): they check what compiles and links, and their numbers do not
# depend on it.
# binbow::dbow2: an ORB-SLAM text vocabulary made by the installed CLI, and
# DBoW2's own numbers to reproduce.
set(orbvoc ${WORK_DIR}/ORBvoc.txt)
run("converting the vocabulary for the dbow2 consumer" ${cli} convert ${vocabulary} ${orbvoc})
set(build ${WORK_DIR}/dbow2-cmake)
run("configuring the dbow2 consumer" ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR}/dbow2
    -B ${build} -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=)
run("building the dbow2 consumer" ${CMAKE_COMMAND} --build ${build})
run("running the dbow2 consumer" ${build}/consumer ${orbvoc} ${CONSUMER_SOURCE_DIR}/../compat/dbow2_golden.txt)
if(NOT output MATCHES "numbers equal to DBoW2's: [1-9][0-9]*, mismatches: 0")
  message(FATAL_ERROR "the dbow2 consumer printed: ${output}")
endif()
expect_linkage(${build}/consumer dbow2)
message(STATUS "CMake dbow2: ${output}")
# Declaring the CMake versions of the projects written for DBoW2
# (DLoopDetector and ORB-SLAM2 declare 2.8), whose policies the package's
# files run under.
foreach(minimum 2.8.12 3.0 3.5)
  set(build ${WORK_DIR}/dbow2-cmake-${minimum})
  run("configuring the dbow2 consumer as a CMake ${minimum} project" ${CMAKE_COMMAND}
      -S ${CONSUMER_SOURCE_DIR}/dbow2 -B ${build} -DCMAKE_PREFIX_PATH=${prefix}
      -DCMAKE_BUILD_TYPE= -DCONSUMER_CMAKE_MINIMUM=${minimum})
  run("building the dbow2 consumer as a CMake ${minimum} project" ${CMAKE_COMMAND} --build ${build})
  run("running the dbow2 consumer built as a CMake ${minimum} project" ${build}/consumer ${orbvoc}
      ${CONSUMER_SOURCE_DIR}/../compat/dbow2_golden.txt)
  if(NOT output MATCHES "numbers equal to DBoW2's: [1-9][0-9]*, mismatches: 0")
    message(FATAL_ERROR "the dbow2 consumer built as a CMake ${minimum} project printed: ${output}")
  endif()
endforeach()

# binbow::dbow2_names: code written as DLoopDetector and ORB-SLAM2/3 call
# DBoW2, their include lines unchanged (tests/package/dbow2_names), each
# program checked against DBoW2's numbers. ORB-SLAM3's Boost.Serialization
# of the vectors is built where Boost's library is found.
set(golden ${CONSUMER_SOURCE_DIR}/../compat/dbow2_golden.txt)
set(dbow2_expect "numbers equal to DBoW2's: [1-9][0-9]*, mismatches: 0")
function(run_dbow2_names_consumers directory how)
  set(programs dloopdetector orbslam)
  if(EXISTS ${directory}/orbslam3_serialization)
    list(APPEND programs orbslam3_serialization)
  endif()
  foreach(program ${programs})
    if(program STREQUAL "dloopdetector")
      set(arguments ${vocabulary} ${golden})
    else()
      set(arguments ${orbvoc} ${golden})
    endif()
    run("running the dbow2_names consumer ${program} (${how})" ${directory}/${program} ${arguments})
    if(NOT output MATCHES "${dbow2_expect}")
      message(FATAL_ERROR "the dbow2_names consumer ${program} built with ${how} printed: ${output}")
    endif()
    expect_linkage(${directory}/${program} dbow2)
    message(STATUS "${how} dbow2_names ${program}: ${output}")
  endforeach()
  if(NOT EXISTS ${directory}/orbslam3_serialization)
    message(STATUS "${how} dbow2_names: Boost.Serialization not found, "
                   "ORB-SLAM3's archives of the vectors not tested")
  endif()
endfunction()
set(names_build ${WORK_DIR}/dbow2_names-cmake)
run("configuring the dbow2_names consumer" ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR}/dbow2_names
    -B ${names_build} -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=)
run("building the dbow2_names consumer" ${CMAKE_COMMAND} --build ${names_build})
run_dbow2_names_consumers(${names_build} CMake)

# pkg-config: binbow (core) and binbow-vision.
foreach(consumer core vision)
  if(consumer STREQUAL "core")
    set(module binbow)
    set(private_requirements zlib)
  else()
    set(module binbow-vision)
    set(private_requirements libjpeg)
  endif()
  # The consumer chooses its C++ standard (C++17 or later).
  run("pkg-config --cflags ${module}" pkg-config --cflags ${module})
  if(output MATCHES "-std=")
    message(FATAL_ERROR "pkg-config --cflags ${module} imposes a C++ standard: ${output}")
  endif()
  # A shared library's own dependencies are not the consumer's to link.
  run("pkg-config --print-requires ${module}" pkg-config --print-requires ${module})
  foreach(requirement ${private_requirements})
    if(SHARED AND output MATCHES "(^|\n)${requirement}")
      message(FATAL_ERROR "pkg-config ${module} makes ${requirement} public in a shared build: ${output}")
    endif()
  endforeach()
  run("pkg-config ${module}" pkg-config --cflags --libs ${module})
  string(STRIP "${output}" flags)
  separate_arguments(flags UNIX_COMMAND "${flags}")
  set(program ${WORK_DIR}/${consumer}-pkgconfig)
  # The rpath lets the program find a shared binbow in the scratch prefix.
  run("building the ${consumer} consumer with pkg-config" ${CXX} -std=c++17 -O1
      ${CONSUMER_SOURCE_DIR}/${consumer}/main.cpp -o ${program} ${flags}
      -Wl,-rpath,${prefix}/${LIBDIR})
  run("running the ${consumer} consumer (pkg-config)" ${program} ${vocabulary} ${sample})
  if(NOT output MATCHES "${${consumer}_expect}")
    message(FATAL_ERROR "the ${consumer} consumer built with pkg-config printed: ${output}")
  endif()
  expect_linkage(${program} ${consumer})
  message(STATUS "pkg-config ${consumer}: ${output}")
endforeach()

# pkg-config: binbow-dbow2, as C++11.
run("pkg-config binbow-dbow2" pkg-config --cflags --libs binbow-dbow2)
string(STRIP "${output}" flags)
separate_arguments(flags UNIX_COMMAND "${flags}")
set(program ${WORK_DIR}/dbow2-pkgconfig)
run("building the dbow2 consumer with pkg-config" ${CXX} -std=c++11 -O0
    -I${CONSUMER_SOURCE_DIR}/../compat ${CONSUMER_SOURCE_DIR}/dbow2/main.cpp -o ${program} ${flags}
    -Wl,-rpath,${prefix}/${LIBDIR})
run("running the dbow2 consumer (pkg-config)" ${program} ${orbvoc}
    ${CONSUMER_SOURCE_DIR}/../compat/dbow2_golden.txt)
if(NOT output MATCHES "numbers equal to DBoW2's: [1-9][0-9]*, mismatches: 0")
  message(FATAL_ERROR "the dbow2 consumer built with pkg-config printed: ${output}")
endif()
expect_linkage(${program} dbow2)
message(STATUS "pkg-config dbow2: ${output}")

# pkg-config: binbow-dbow2-names, as C++11, the same sources as the CMake
# consumer; Boost.Serialization where that one found it.
run("pkg-config binbow-dbow2-names" pkg-config --cflags --libs binbow-dbow2-names)
string(STRIP "${output}" flags)
separate_arguments(flags UNIX_COMMAND "${flags}")
set(names_programs ${WORK_DIR}/dbow2_names-pkgconfig)
file(MAKE_DIRECTORY ${names_programs})
set(programs dloopdetector orbslam)
if(EXISTS ${names_build}/orbslam3_serialization)
  list(APPEND programs orbslam3_serialization)
endif()
foreach(program ${programs})
  set(extra)
  if(program STREQUAL "orbslam3_serialization")
    set(extra -lboost_serialization)
  endif()
  run("building the dbow2_names consumer ${program} with pkg-config" ${CXX} -std=c++11 -O0
      -I${CONSUMER_SOURCE_DIR}/../compat ${CONSUMER_SOURCE_DIR}/dbow2_names/${program}.cpp
      -o ${names_programs}/${program} ${flags} ${extra} -Wl,-rpath,${prefix}/${LIBDIR})
endforeach()
run_dbow2_names_consumers(${names_programs} pkg-config)

# Code written as VINS calls its copy of DBoW2 (VINS's include names from
# binbow-dbow2-names, DVision::BRIEF's boost::dynamic_bitset descriptors, a
# VINS binary vocabulary, VINS's query rule), as C++14 through CMake and
# pkg-config, against DBoW2's numbers as VINS's copy returns them.
set(vins_vocabulary ${WORK_DIR}/brief_k10L6.bin)
run("converting the vocabulary for the vins consumer" ${cli} convert ${prefix}/share/binbow/vocab/orb_default.bbw
    ${vins_vocabulary} --to vins)
set(vins_expect "numbers equal to DBoW2's: [1-9][0-9]*, mismatches: 0, newest entry returned: [1-9]")
set(golden ${CONSUMER_SOURCE_DIR}/../compat/dbow2_golden.txt)
set(build ${WORK_DIR}/vins-cmake)
run("configuring the vins consumer" ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR}/vins -B ${build}
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=)
run("building the vins consumer" ${CMAKE_COMMAND} --build ${build})
run("running the vins consumer" ${build}/consumer ${vins_vocabulary} ${golden})
if(NOT output MATCHES "${vins_expect}")
  message(FATAL_ERROR "the vins consumer printed: ${output}")
endif()
expect_linkage(${build}/consumer dbow2)
message(STATUS "CMake vins: ${output}")
run("pkg-config binbow-dbow2-names" pkg-config --cflags --libs binbow-dbow2-names binbow-dbow2 opencv4)
string(STRIP "${output}" flags)
separate_arguments(flags UNIX_COMMAND "${flags}")
set(program ${WORK_DIR}/vins-pkgconfig)
run("building the vins consumer with pkg-config" ${CXX} -std=c++14 -O0
    -I${CONSUMER_SOURCE_DIR}/../compat -I${CONSUMER_SOURCE_DIR}/../compat_vins
    ${CONSUMER_SOURCE_DIR}/vins/main.cpp -o ${program} ${flags} -Wl,-rpath,${prefix}/${LIBDIR})
run("running the vins consumer (pkg-config)" ${program} ${vins_vocabulary} ${golden})
if(NOT output MATCHES "${vins_expect}")
  message(FATAL_ERROR "the vins consumer built with pkg-config printed: ${output}")
endif()
expect_linkage(${program} dbow2)
message(STATUS "pkg-config vins: ${output}")
