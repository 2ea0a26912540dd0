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
# which the consumer chooses. Dependencies binbow's headers do not show
# (zlib, libjpeg) are private requirements of shared libraries, and
# public ones of static libraries, which cannot link without them.
file(RELATIVE_PATH BINBOW_PC_TO_PREFIX /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
if(BUILD_SHARED_LIBS)
  set(BINBOW_PC_PRIVATE ".private")
else()
  set(BINBOW_PC_PRIVATE "")
endif()
set(BINBOW_PC_FILES binbow binbow-dbow2 binbow-dbow2-names)
if(BINBOW_BUILD_VISION)
  list(APPEND BINBOW_PC_FILES binbow-vision)
endif()
foreach(pc_file ${BINBOW_PC_FILES})
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
