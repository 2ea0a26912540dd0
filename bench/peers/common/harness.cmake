# What every harness project shares: C++17, Release unless told otherwise,
# OpenCV for the images and descriptors, and add_peer_harness(). Included by
# the projects under bench/peers/; nothing here is part of binbow's build.
set(CMAKE_CXX_STANDARD 17)
set(CMAKE_CXX_STANDARD_REQUIRED ON)
if(NOT CMAKE_BUILD_TYPE)
  set(CMAKE_BUILD_TYPE Release)
endif()
set(BINBOW_INCLUDE_DIR ${CMAKE_CURRENT_LIST_DIR}/../../../include CACHE PATH "binbow headers")
set(PEER_COMMON_DIR ${CMAKE_CURRENT_LIST_DIR})
find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc imgcodecs features2d)
find_package(Threads REQUIRED)
find_package(ZLIB REQUIRED)

# add_peer_harness(TARGET SOURCE BINBOW_CORE_LIBRARY PEER_INCLUDE_DIR PEER_LIBRARY):
# one harness linking binbow's static core library and the peer's library.
# -O2, no -march: neither library's hot code is in the harness itself.
function(add_peer_harness target source binbow_core peer_include_dir peer_library)
  add_executable(${target} ${source})
  target_compile_options(${target} PRIVATE -O2 -Wall -Wextra)
  target_include_directories(${target} PRIVATE ${BINBOW_INCLUDE_DIR} ${PEER_COMMON_DIR})
  target_include_directories(${target} SYSTEM PRIVATE ${peer_include_dir} ${OpenCV_INCLUDE_DIRS})
  target_link_libraries(${target} PRIVATE ${binbow_core} ${peer_library} opencv_core
                        opencv_imgproc opencv_imgcodecs opencv_features2d Threads::Threads
                        ZLIB::ZLIB ${CMAKE_DL_LIBS})
  get_filename_component(peer_library_dir ${peer_library} DIRECTORY)
  set_target_properties(${target} PROPERTIES BUILD_RPATH "${peer_library_dir}")
endfunction()
