#include "core/kernels.h"

#include <cstdlib>
#include <cstring>
#include <string>

#include "binbow/error.h"

namespace binbow::detail {

namespace generic {
const Kernels& get();
}
#if !defined(BINBOW_NEON_DISPATCH)
namespace popcnt {
const Kernels& get();
}
#endif
#if defined(BINBOW_X86_DISPATCH)
namespace avx2 {
const Kernels& get();
}
namespace avx512 {
const Kernels& get();
}
#endif
#if defined(BINBOW_NEON_DISPATCH)
namespace neon {
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
    // Both are compiled with -mpopcnt as well. GCC's checks include the OS's
    // consent to save the AVX and AVX-512 states (XCR0).
    if (__builtin_cpu_supports("avx2")) all.push_back(&avx2::get());
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vpopcntdq"))
      all.push_back(&avx512::get());
  }
#elif defined(BINBOW_NEON_DISPATCH)
  all.push_back(&neon::get());
#else
  all.push_back(&popcnt::get());
#endif
  return all;
}

std::vector<CpuFeatureFlag> kernel_cpu_features() {
#if defined(BINBOW_X86_DISPATCH)
  __builtin_cpu_init();
  return {{"popcnt", __builtin_cpu_supports("popcnt") != 0},
          {"avx2", __builtin_cpu_supports("avx2") != 0},
          {"avx512f", __builtin_cpu_supports("avx512f") != 0},
          {"avx512vpopcntdq", __builtin_cpu_supports("avx512vpopcntdq") != 0}};
#else
  return {};
#endif
}

const Kernels& select_kernels(const char* requested) {
  const std::vector<const Kernels*> supported = supported_kernels();
  // The list goes from the most portable set to the fastest.
  if (requested == nullptr || *requested == '\0') return *supported.back();
  std::string names;
  for (const Kernels* k : supported) {
    if (std::strcmp(k->name, requested) == 0) return *k;
    names += (names.empty() ? "" : ", ") + std::string(k->name);
  }
  bool known = false;
  for (const char* name : {"generic", "popcnt", "avx2", "avx512", "neon"})
    known = known || std::strcmp(name, requested) == 0;
  throw InvalidArgument(std::string(kKernelVariable) + "=" + requested + ": " +
                        (known ? "this CPU cannot run that Hamming kernel"
                               : "no such Hamming kernel (binbow has generic, popcnt, avx2, "
                                 "avx512 and neon)") +
                        "; this CPU supports " + names + ": set " + kKernelVariable +
                        " to one of them, or unset it to use the fastest");
}

const Kernels& kernels() {
  static const Kernels& chosen = select_kernels(std::getenv(kKernelVariable));
  return chosen;
}

}  // namespace binbow::detail
