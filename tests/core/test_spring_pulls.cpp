// The projective solver's spring pass (core/src/spring_pulls.h) on every SIMD target this
// build compiled and this machine runs: each pull and energy the scalar formula's bits.
#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "drape/ccd/types.h"
#include "spring_pulls.h"

namespace drape {
namespace {

struct Spring {
  Vec3 z, start, direction;
  double rest, elastic, viscous;
};

// The formula as the solver's scalar evaluation writes it (projective.cpp, evaluate).
void scalar_pull(const Spring& s, Vec3& pull, double& energy) {
  const Scalar length = s.z.norm();
  const Vec3 d = length > 0 ? Vec3(s.z * (1 / length)) : s.direction;
  const Scalar along = (s.z - s.start).dot(s.direction);
  pull = s.elastic * (length - s.rest) * d + s.viscous * along * s.direction;
  energy = 0.5 * s.elastic * (length - s.rest) * (length - s.rest) + 0.5 * s.viscous * along * along;
}

// Springs from 1e-8 to 1e3 m long, some of zero length, some at rest, some without damping.
std::vector<Spring> springs(std::size_t count) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(-1, 1), exponent(-8, 3);
  const auto vector = [&] { return Vec3(unit(random), unit(random), unit(random)); };
  std::vector<Spring> out;
  for (std::size_t k = 0; k < count; ++k) {
    Spring s;
    const double scale = std::pow(10.0, exponent(random));
    s.z = k % 7 == 3 ? Vec3::Zero() : Vec3(scale * vector());
    s.start = scale * vector();
    s.direction = s.start.norm() > 0 ? Vec3(s.start.normalized()) : Vec3::UnitX();
    s.rest = k % 5 == 1 ? s.z.norm() : scale * std::abs(unit(random));
    s.elastic = std::pow(10.0, exponent(random));
    s.viscous = k % 4 == 2 ? 0.0 : std::pow(10.0, exponent(random));
    out.push_back(s);
  }
  return out;
}

TEST(SpringPulls, EveryTargetGivesTheScalarFormulasBits) {
  const std::size_t count = 37 * SPRING_LANES;
  const std::vector<Spring> input = springs(count);
  std::vector<double> zx, zy, zz, sx, sy, sz, dx, dy, dz, rest, elastic, viscous;
  for (const Spring& s : input) {
    zx.push_back(s.z.x()), zy.push_back(s.z.y()), zz.push_back(s.z.z());
    sx.push_back(s.start.x()), sy.push_back(s.start.y()), sz.push_back(s.start.z());
    dx.push_back(s.direction.x()), dy.push_back(s.direction.y()), dz.push_back(s.direction.z());
    rest.push_back(s.rest), elastic.push_back(s.elastic), viscous.push_back(s.viscous);
  }
  // core's own list (its build's targets, not this file's); the dispatch restored however the
  // loop ends.
  const std::vector<std::int64_t> targets = spring_pull_targets();
  ASSERT_FALSE(targets.empty());
  struct Restore {
    ~Restore() { hwy::SetSupportedTargetsForTest(0); }
  } restore;
  for (const std::int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    SCOPED_TRACE(hwy::TargetName(target));
    std::vector<double> px(count), py(count), pz(count), energy(count);
    spring_pulls({zx.data(), zy.data(), zz.data(), sx.data(), sy.data(), sz.data(), dx.data(), dy.data(), dz.data(),
                  rest.data(), elastic.data(), viscous.data(), count},
                 {px.data(), py.data(), pz.data(), energy.data()});
    for (std::size_t k = 0; k < count; ++k) {
      Vec3 pull;
      double e = 0;
      scalar_pull(input[k], pull, e);
      ASSERT_EQ(Vec3(px[k], py[k], pz[k]), pull) << "spring " << k;
      ASSERT_EQ(energy[k], e) << "spring " << k;
    }
  }
}

}  // namespace
}  // namespace drape
