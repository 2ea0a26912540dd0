// Compiled with -mpopcnt -mavx512f -mavx512vpopcntdq on x86-64 only (see
// src/CMakeLists.txt); only called when the CPU and the OS support both.
#include <algorithm>

#define BINBOW_KERNEL_NAMESPACE avx512
#define BINBOW_KERNEL_NAME "avx512"
#define BINBOW_KERNEL_AVX512
#include "core/kernels_impl.h"
