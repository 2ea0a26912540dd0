# Warnings for binbow's own targets (not for third-party headers).
option(BINBOW_WARNINGS_AS_ERRORS "Treat compiler warnings in binbow's own code as errors" OFF)
function(binbow_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor)
  if(BINBOW_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
