// Compiled with -mpopcnt on x86-64 (see src/CMakeLists.txt); only called when
// the CPU reports popcnt. Not compiled on aarch64, whose NEON kernel counts
// bits in vectors.
#include <algorithm>

#define BINBOW_KERNEL_NAMESPACE popcnt
#define BINBOW_KERNEL_NAME "popcnt"
#include "core/kernels_impl.h"
