include(CMakePackageConfigHelpers)

install(TARGETS binbow_core binbow_vision EXPORT binbowTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS binbow RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY include/binbow DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT binbowTargets NAMESPACE binbow::
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/binbow)

configure_package_config_file(cmake/binbowConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/binbowConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/binbow)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/binbowConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/binbowConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/binbowConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/binbow)

# Bundled data, found by the CLI at <prefix>/share/binbow (default vocabularies, demo sample).
install(DIRECTORY data/vocab data/samples DESTINATION ${CMAKE_INSTALL_DATADIR}/binbow)
