include(CMakePackageConfigHelpers)

# Export sets per component, so that a consumer of binbow::core alone needs no OpenCV:
# binbowConfig.cmake loads the vision targets only when their dependencies are found.
install(TARGETS binbow_core EXPORT binbowCoreTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
if(BINBOW_BUILD_VISION)
  install(TARGETS binbow_vision EXPORT binbowVisionTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
          INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endif()
# binbow::dbow2 (DBoW2's API) needs OpenCV core only; binbow::dbow2_names
# (DBoW2's include names) is a folder of the installed headers on top of it.
install(TARGETS binbow_dbow2 binbow_dbow2_names EXPORT binbowDbow2Targets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS binbow RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The image/video module, loaded by binbow::vision on first use (src/media/),
# and the CLI's commands that need OpenCV (apps/binbow/vision_commands.h).
if(BINBOW_BUILD_VISION)
  install(TARGETS binbow_media binbow_cli_vision LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/binbow)
endif()
install(DIRECTORY include/binbow DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT binbowCoreTargets NAMESPACE binbow::
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/binbow)
if(BINBOW_BUILD_VISION)
  install(EXPORT binbowVisionTargets NAMESPACE binbow::
          DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/binbow)
endif()
install(EXPORT binbowDbow2Targets NAMESPACE binbow::
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/binbow)

configure_package_config_file(cmake/binbowConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/binbowConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/binbow)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/binbowConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/binbowConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/binbowConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/binbow)

# pkg-config files for builds without CMake, relocatable (the prefix is found
# from the file's own folder). No -std= flag: binbow needs C++17 or later,
# which the consumer chooses. Each field appears once: Ubuntu 20.04's and
# 22.04's pkg-config keep only the last of two Requires: lines (the ctest
# release.pc_files parses them strictly). Dependencies binbow's headers do
# not show (zlib, libjpeg, libdl) are private to a shared library
# (Requires.private, Libs.private: pkg-config --static lists them), and
# public for a static one, which cannot link without them.
file(RELATIVE_PATH BINBOW_PC_TO_PREFIX /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
set(binbow_pc_private_libs)
foreach(library ${CMAKE_DL_LIBS})
  list(APPEND binbow_pc_private_libs -l${library})
endforeach()
set(binbow_pc_public_requires "")
set(binbow_pc_private_requires zlib)
set(binbow-vision_pc_public_requires binbow opencv4)
set(binbow-vision_pc_private_requires libjpeg)
set(binbow-dbow2_pc_public_requires opencv4)
set(binbow-dbow2_pc_private_requires zlib)
# binbow-dbow2-names only adds an include folder to binbow-dbow2.
set(binbow-dbow2-names_pc_public_requires binbow-dbow2)
set(BINBOW_PC_FILES binbow binbow-dbow2 binbow-dbow2-names)
if(BINBOW_BUILD_VISION)
  list(APPEND BINBOW_PC_FILES binbow-vision)
endif()
foreach(pc_file ${BINBOW_PC_FILES})
  set(public ${${pc_file}_pc_public_requires})
  set(private ${${pc_file}_pc_private_requires})
  set(private_libs ${binbow_pc_private_libs})
  if(pc_file STREQUAL "binbow-dbow2-names")
    set(private_libs)  # no library of its own
  endif()
  if(NOT BUILD_SHARED_LIBS)
    list(APPEND public ${private})
    set(private)
  endif()
  # Whole lines, only the fields with something to say.
  set(BINBOW_PC_DEPENDENCIES)
  if(public)
    string(REPLACE ";" " " public "${public}")
    list(APPEND BINBOW_PC_DEPENDENCIES "Requires: ${public}")
  endif()
  if(private)
    string(REPLACE ";" " " private "${private}")
    list(APPEND BINBOW_PC_DEPENDENCIES "Requires.private: ${private}")
  endif()
  string(REPLACE ";" " " private_libs "${private_libs}")
  set(BINBOW_PC_LIBS "")
  if(private_libs AND BUILD_SHARED_LIBS)
    list(APPEND BINBOW_PC_DEPENDENCIES "Libs.private: ${private_libs}")
  elseif(private_libs)
    set(BINBOW_PC_LIBS " ${private_libs}")
  endif()
  string(REPLACE ";" "\n" BINBOW_PC_DEPENDENCIES "${BINBOW_PC_DEPENDENCIES}")
  configure_file(cmake/${pc_file}.pc.in ${CMAKE_CURRENT_BINARY_DIR}/${pc_file}.pc @ONLY)
  install(FILES ${CMAKE_CURRENT_BINARY_DIR}/${pc_file}.pc
          DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
endforeach()

# Bundled data, found by the CLI at <prefix>/share/binbow (default vocabularies, demo sample).
# Each folder keeps its license notice and provenance (samples/rtabmap/LICENSE,
# vocab/PROVENANCE.md) next to the files.
install(DIRECTORY data/vocab data/samples DESTINATION ${CMAKE_INSTALL_DATADIR}/binbow)
# binbow's license and the origin and license of every third-party file; the
# built-in BRIEF pattern's license asks binary distributions to carry its notice.
install(FILES LICENSE THIRD_PARTY.md DESTINATION ${CMAKE_INSTALL_DOCDIR})

# For ROS 2: colcon and rosdep read package.xml in the source, ROS 2's tools
# (ros2 pkg, ament_index) find an installed package by its empty marker in
# the ament resource index, and its manifest in share/<package>.
install(FILES package.xml DESTINATION ${CMAKE_INSTALL_DATADIR}/binbow)
file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/ament_index/binbow "")
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/ament_index/binbow
        DESTINATION ${CMAKE_INSTALL_DATADIR}/ament_index/resource_index/packages)
