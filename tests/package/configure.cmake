# Configures a consumer project against the installed package and checks what
# find_package(binbow) said: EXPECT_FAILURE (ON or OFF) and every text of
# EXPECT (a list) in the output, with CMake's line wrapping undone.
# cmake -DSOURCE=... -DBUILD=... -DPREFIX=... [-DARGS=...] -DEXPECT_FAILURE=ON|OFF
#       -DEXPECT="text;text" -P configure.cmake
file(REMOVE_RECURSE ${BUILD})
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE} -B ${BUILD} -DCMAKE_PREFIX_PATH=${PREFIX}
                        ${ARGS}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
set(output "${out}\n${err}")
if(EXPECT_FAILURE AND NOT rc)
  message(FATAL_ERROR "configuring ${SOURCE} (${ARGS}) succeeded, expected it to fail:\n${output}")
elseif(NOT EXPECT_FAILURE AND rc)
  message(FATAL_ERROR "configuring ${SOURCE} (${ARGS}) failed (${rc}):\n${output}")
endif()
string(REGEX REPLACE "[ \t\r\n]+" " " flat "${output}")
foreach(text IN LISTS EXPECT)
  string(FIND "${flat}" "${text}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "configuring ${SOURCE} (${ARGS}) did not say \"${text}\":\n${output}")
  endif()
  message(STATUS "said: ${text}")
endforeach()
