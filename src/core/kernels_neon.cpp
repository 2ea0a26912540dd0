// Compiled on aarch64 only (see src/CMakeLists.txt), where NEON is part of
// every CPU.
#include <algorithm>

#define BINBOW_KERNEL_NAMESPACE neon
#define BINBOW_KERNEL_NAME "neon"
#define BINBOW_KERNEL_NEON
#include "core/kernels_impl.h"
