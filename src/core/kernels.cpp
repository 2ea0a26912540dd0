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

const Kernels& generic_kernels() {
  return generic::get();
}

std::vector<const Kernels*> supported_kernels() {
  std::vector<const Kernels*> all{&generic::get()};
#if defined(BINBOW_X86_DISPATCH)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("popcnt")) {
    all.push_back(&popcnt::get());
    // Compiled with -mpopcnt as well. GCC's check includes the OS's consent
    // to save the AVX-512 state (XCR0).
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vpopcntdq"))
      all.push_back(&avx512::get());
  }
#else
  all.push_back(&popcnt::get());
#endif
  return all;
}

std::vector<CpuFeatureFlag> kernel_cpu_features() {
#if defined(BINBOW_X86_DISPATCH)
  __builtin_cpu_init();
  return {{"popcnt", __builtin_cpu_supports("popcnt") != 0},
          {"avx512f", __builtin_cpu_supports("avx512f") != 0},
          {"avx512vpopcntdq", __builtin_cpu_supports("avx512vpopcntdq") != 0}};
#else
  return {};
#endif
}

const Kernels& kernels() {
  // The list goes from the most portable set to the fastest.
  static const Kernels& chosen = *supported_kernels().back();
  return chosen;
}

}  // namespace binbow::detail
