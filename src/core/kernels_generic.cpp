#include <algorithm>

#define BINBOW_KERNEL_NAMESPACE generic
#define BINBOW_KERNEL_NAME "generic"
#include "core/kernels_impl.h"
