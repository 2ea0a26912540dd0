#include "core/kernels.h"

namespace binbow::detail {

namespace generic {
const Kernels& get();
}
namespace popcnt {
const Kernels& get();
}

const Kernels& generic_kernels() {
  return generic::get();
}

const Kernels& kernels() {
  static const Kernels& chosen = []() -> const Kernels& {
#if defined(BINBOW_X86_DISPATCH)
    __builtin_cpu_init();
    if (__builtin_cpu_supports("popcnt")) return popcnt::get();
    return generic::get();
#else
    return popcnt::get();
#endif
  }();
  return chosen;
}

}  // namespace binbow::detail
