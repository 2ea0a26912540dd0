// Compiled with -mavx2 -mpopcnt on x86-64 only (see src/CMakeLists.txt); only
// called when the CPU and the OS support both.
#include <algorithm>

#define BINBOW_KERNEL_NAMESPACE avx2
#define BINBOW_KERNEL_NAME "avx2"
#define BINBOW_KERNEL_AVX2
#include "core/kernels_impl.h"
