#include "core/kernels.h"

namespace binbow::detail {

namespace generic {
const Kernels& get();
}
namespace popcnt {
const Kernels& get();
}
#if defined(BINBOW_X86_DISPATCH)
namespace avx512 {
const Kernels& get();
}
#endif

namespace {

#if defined(BINBOW_X86_DISPATCH)
bool has_avx512_popcount() {
  // GCC's check includes the OS's consent to save the AVX-512 state (XCR0).
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vpopcntdq");
}
#endif

}  // namespace

const Kernels& generic_kernels() {
  return generic::get();
}

const Kernels& kernels() {
  static const Kernels& chosen = []() -> const Kernels& {
#if defined(BINBOW_X86_DISPATCH)
    __builtin_cpu_init();
    if (has_avx512_popcount()) return avx512::get();
    if (__builtin_cpu_supports("popcnt")) return popcnt::get();
    return generic::get();
#else
    return popcnt::get();
#endif
  }();
  return chosen;
}

std::vector<const Kernels*> supported_kernels() {
  std::vector<const Kernels*> all{&generic::get()};
#if defined(BINBOW_X86_DISPATCH)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("popcnt")) all.push_back(&popcnt::get());
  if (has_avx512_popcount()) all.push_back(&avx512::get());
#else
  all.push_back(&popcnt::get());
#endif
  return all;
}

}  // namespace binbow::detail
