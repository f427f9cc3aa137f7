// Whether the AVX2 kernels run (avx2.h).
#include "avx2.h"

namespace drape::ccd::detail {

bool portable_kernels = false;

bool avx2_only = false;

#if DRAPE_X86_KERNELS
const bool cpu_has_avx2 = [] {
  __builtin_cpu_init();  // needed when this runs before main, as static initialisation does
  return __builtin_cpu_supports("avx2") != 0;
}();

const bool cpu_has_avx512 = [] {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f") != 0 && __builtin_cpu_supports("avx512dq") != 0;
}();
#else
const bool cpu_has_avx2 = false;  // no x86 kernels in this build: the portable code answers
const bool cpu_has_avx512 = false;
#endif

}  // namespace drape::ccd::detail
