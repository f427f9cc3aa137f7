// The AVX2 helpers (ccd/src/avx2.h): each is the scalar operation it stands for, bit for bit,
// NaN, signed zeros and infinities included; the point loads give a point's coordinates.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "avx2.h"
#include "drape/ccd/coplanarity.h"

using namespace drape;
using namespace drape::ccd;

#if DRAPE_X86_KERNELS
namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

__attribute__((target("avx2"))) void apply(const double (&a)[4], const double (&b)[4], double (&max)[4],
                                           double (&min)[4], double (&abs)[4]) {
  const __m256d x = _mm256_loadu_pd(a), y = _mm256_loadu_pd(b);
  _mm256_storeu_pd(max, detail::max4(x, y));
  _mm256_storeu_pd(min, detail::min4(x, y));
  _mm256_storeu_pd(abs, detail::abs4(x));
}

__attribute__((target("avx2"))) bool culls(const Bernstein3& b, Scalar error) {
  return detail::filter_culls_avx2(_mm256_loadu_pd(b.data()), error);
}

__attribute__((target("avx2"))) void load(const Query& q, int i, double (&start)[4], double (&end)[4]) {
  _mm256_storeu_pd(start, detail::load_start(q, i));
  _mm256_storeu_pd(end, detail::load_end(q, i));
}

}  // namespace

TEST(Avx2, MinMaxAbsAreTheStdFunctions) {
  if (!detail::cpu_has_avx2) GTEST_SKIP() << "no AVX2 on this machine";
  const double inf = std::numeric_limits<double>::infinity();
  const double values[] = {std::numeric_limits<double>::quiet_NaN(), -0.0, 0.0, 1.0, -1.0, inf, -inf,
                           std::numeric_limits<double>::denorm_min(), 2.5};
  std::size_t checked = 0;
  for (double a : values)
    for (double b : values) {
      const double x[4] = {a, b, a, -a}, y[4] = {b, a, -b, b};
      double max[4], min[4], abs[4];
      apply(x, y, max, min, abs);
      for (int lane = 0; lane < 4; ++lane) {
        EXPECT_TRUE(same_bits(max[lane], std::max(x[lane], y[lane]))) << x[lane] << " " << y[lane];
        EXPECT_TRUE(same_bits(min[lane], std::min(x[lane], y[lane]))) << x[lane] << " " << y[lane];
        EXPECT_TRUE(same_bits(abs[lane], std::abs(x[lane]))) << x[lane];
        ++checked;
      }
    }
  EXPECT_EQ(checked, 4u * 81u);
}

TEST(Avx2, FilterDecisionIsFilterCulls) {
  // Every combination of four coefficients from a set of values around the decision's edges
  // (signs, zeros, within and beyond 2048 errors, infinities, NaN) and three errors.
  if (!detail::cpu_has_avx2) GTEST_SKIP() << "no AVX2 on this machine";
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  const double values[] = {nan, -0.0, 0.0, 1e-3, -1e-3, 1.5, -1.5, 1e3, -1e3, inf, -inf};
  std::size_t checked = 0, culled = 0;
  for (double error : {0.0, 1e-3, 1.0, nan})
    for (double b0 : values)
      for (double b1 : values)
        for (double b2 : values)
          for (double b3 : values) {
            CoplanarityCubic c;
            c.b = {b0, b1, b2, b3};
            c.error = error;
            const bool expected = filter_culls(c);
            ASSERT_EQ(culls(c.b, error), expected) << b0 << " " << b1 << " " << b2 << " " << b3 << " error " << error;
            ++checked;
            culled += expected;
          }
  EXPECT_GT(culled, 1000u);  // both answers occur (2,274 of 58,564)
}

TEST(Avx2, PointLoadsGiveThePoint) {
  if (!detail::cpu_has_avx2) GTEST_SKIP() << "no AVX2 on this machine";
  Query q;
  for (int i = 0; i < 4; ++i) {
    q.start[i] = Vec3(10 * i + 1, 10 * i + 2, 10 * i + 3);
    q.end[i] = Vec3(-10 * i - 1, -10 * i - 2, -10 * i - 3);
  }
  for (int i = 0; i < 4; ++i) {
    double start[4], end[4];
    load(q, i, start, end);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(start[k], q.start[i][k]) << i << " " << k;
      EXPECT_EQ(end[k], q.end[i][k]) << i << " " << k;
    }
  }
}

#else
TEST(Avx2, NotInThisBuild) { GTEST_SKIP() << "built with the portable kernels alone (DRAPE_PORTABLE_KERNELS)"; }
#endif  // DRAPE_X86_KERNELS
