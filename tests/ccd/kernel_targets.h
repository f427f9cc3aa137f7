#pragma once
// Runs a test's body once on every SIMD target of the CCD kernels (ccd/src/kernels.h) that
// this build compiled and this machine runs, then lets the dispatch choose again.
#include <gtest/gtest.h>

#include "kernels.h"

namespace drape::ccd::kernel_testing {

template <class Body>
void on_every_kernel_target(Body body) {
  for (const std::int64_t target : detail::kernel_targets()) {
    detail::use_kernel_target(target);
    SCOPED_TRACE("kernel target " + detail::kernel_target_name());
    body();
  }
  detail::use_kernel_target(0);
}

/// The portable one-lane target (every build has it), as the reference of the others.
inline std::int64_t portable_kernel_target() { return detail::kernel_targets().back(); }

}  // namespace drape::ccd::kernel_testing
