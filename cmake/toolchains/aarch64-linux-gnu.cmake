# Cross-compiles for 64-bit ARM Linux (Jetson, Raspberry Pi with a 64-bit OS)
# with Debian's g++-aarch64-linux-gnu. The target's libraries are Debian's arm64
# packages installed beside the build machine's through multiarch
# (`dpkg --add-architecture arm64`, then zlib1g-dev:arm64 and the like), in
# /usr/lib/aarch64-linux-gnu, where CMake looks for this architecture's
# libraries and packages. The programs built run under qemu-aarch64
# (Debian's qemu-user), which finds the arm64 loader and libraries there too.
#   cmake -S . -B build-aarch64 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/aarch64-linux-gnu.cmake
# scripts/test-aarch64.sh builds and tests binbow so.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64)
# pkg-config reads the target's .pc files, not the build machine's.
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/share/pkgconfig")
