# Installs the build tree into a fresh scratch prefix, for the tests of the
# installed package (the fixture package.installed of tests/package/CMakeLists.txt).
file(REMOVE_RECURSE ${PREFIX})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BINBOW_BUILD_DIR} --prefix ${PREFIX}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc)
  message(FATAL_ERROR "installing binbow into ${PREFIX} failed (${rc}):\n${out}\n${err}")
endif()
message(STATUS "binbow installed in ${PREFIX}")
