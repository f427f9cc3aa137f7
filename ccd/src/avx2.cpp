// Whether the AVX2 kernels run (avx2.h).
#include "avx2.h"

namespace drape::ccd::detail {

bool portable_kernels = false;

const bool cpu_has_avx2 = [] {
  __builtin_cpu_init();  // needed when this runs before main, as static initialisation does
  return __builtin_cpu_supports("avx2") != 0;
}();

bool avx2_only = false;

const bool cpu_has_avx512 = [] {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f") != 0 && __builtin_cpu_supports("avx512dq") != 0;
}();

}  // namespace drape::ccd::detail
