// The linear solvers' link with the libraries under them (core/src/linear_solver.cpp).
#include <dlfcn.h>
#include <gtest/gtest.h>

// drape's own entry point for an OpenMP parallel region (docs/solvers.md, "No team for
// CHOLMOD's OpenMP regions") is what libcholmod's calls reach only if the dynamic linker finds
// it before libgomp's in the process's global scope, where dlsym looks too: a build that
// stopped exporting it (a hidden symbol, a library loaded after libgomp) fails here, while its
// results stay the same and only the time grows.
extern "C" void GOMP_parallel(void (*body)(void*), void* data, unsigned num_threads, unsigned flags);

TEST(LinearSolver, OpenMpRegionsReachDrapesEntryPointBeforeLibgomps) {
  EXPECT_EQ(dlsym(RTLD_DEFAULT, "GOMP_parallel"), reinterpret_cast<void*>(&GOMP_parallel));
  int runs = 0;
  GOMP_parallel([](void* count) { ++*static_cast<int*>(count); }, &runs, 4, 0);
  EXPECT_EQ(runs, 1);  // the body once, on the calling thread
}
