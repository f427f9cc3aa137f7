// Strain limiting's sweeps (core/src/strain_limit.h) against a plain Gauss-Seidel sweep that
// looks at every limited spring in every sweep.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "drape/core/integrator.h"
#include "strain_limit.h"

using namespace drape;

namespace {

// The plain sweep, every spring looked at in every sweep, the arithmetic written as the
// specification says (docs/materials.md, strain limiting).
StrainSweeps plain_sweeps(const std::vector<Spring>& springs, const std::vector<int>& limited,
                          const std::vector<Vec3>& positions, const std::vector<Scalar>& inverse_mass, Scalar h,
                          int max_sweeps, std::vector<Vec3>& motion, std::vector<Vec3>& also) {
  StrainSweeps done;
  for (int sweep = 0; sweep < max_sweeps; ++sweep) {
    bool passed = false;
    for (int k : limited) {
      const Spring& s = springs[std::size_t(k)];
      const auto i = std::size_t(s.i), j = std::size_t(s.j);
      const Vec3 d = positions[i] + h * motion[i] - positions[j] - h * motion[j];
      const Scalar length = d.norm(), longest = longest_allowed(s, (positions[i] - positions[j]).norm());
      if (!(length > longest)) continue;
      const Scalar wi = inverse_mass[i], wj = inverse_mass[j];
      if (!(wi + wj > 0)) continue;
      const Vec3 change = ((length - longest) / (h * (wi + wj) * length)) * d;
      motion[i] -= wi * change;
      motion[j] += wj * change;
      also[i] -= wi * change, also[j] += wj * change;
      if (wi == 0) done.work += std::max<Scalar>(0, change.dot(motion[i]));
      if (wj == 0) done.work += std::max<Scalar>(0, -change.dot(motion[j]));
      ++done.corrections;
      passed = true;
    }
    if (!passed) break;
  }
  return done;
}

}  // namespace

TEST(StrainLimit, SweepsThatPassOverUnmovedSpringsCorrectAsEverySpringLookedAtDoes) {
  // A 24 x 24 sheet of 1 cm cells (edges and both diagonals limited to 1.1), a few vertices
  // pinned, its start crumpled and partly stretched past the limit, its motion random and
  // large: many springs pass their limit and the sweeps run long.
  const int side = 24;
  const auto at = [&](int x, int y) { return y * side + x; };
  std::mt19937_64 rng(28);
  std::uniform_real_distribution<Scalar> jitter(-0.002, 0.002), speed(-1.5, 1.5);
  std::vector<Vec3> positions;
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) positions.emplace_back(0.01 * x * (x > side / 2 ? 1.12 : 1.0) + jitter(rng), 0.01 * y + jitter(rng), jitter(rng));
  std::vector<Spring> springs;
  const auto link = [&](int a, int b, Scalar rest) {
    Spring s;
    s.i = a, s.j = b, s.rest_length = rest, s.limit = 1.1;
    springs.push_back(s);
  };
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      if (x + 1 < side) link(at(x, y), at(x + 1, y), 0.01);
      if (y + 1 < side) link(at(x, y), at(x, y + 1), 0.01);
      if (x + 1 < side && y + 1 < side) link(at(x, y), at(x + 1, y + 1), 0.01 * std::sqrt(2.0)), link(at(x + 1, y), at(x, y + 1), 0.01 * std::sqrt(2.0));
    }
  std::vector<int> limited(springs.size());
  for (std::size_t k = 0; k < limited.size(); ++k) limited[k] = int(k);
  std::shuffle(limited.begin(), limited.end(), rng);  // any order: the sweeps keep it
  std::vector<Scalar> inverse_mass(positions.size(), 1 / 0.0002);
  for (int v : {at(0, 0), at(side - 1, 0), at(side / 2, side / 2)}) inverse_mass[std::size_t(v)] = 0;
  const Scalar h = 0.01;
  StrainSweepRecord record;
  // Each case's sweeps against the plain ones, with a sweep cap of 1, 3 and 200.
  const auto check = [&](const char* name, const std::vector<Vec3>& start, const std::vector<Vec3>& start_motion) {
    for (int max_sweeps : {1, 3, 200}) {
      std::vector<Vec3> motion = start_motion, also(start.size(), Vec3::Zero());
      std::vector<Vec3> plain_motion = start_motion, plain_also = also;
      const StrainSweeps fast = limit_strain_sweeps({springs, limited, start, inverse_mass, h, max_sweeps}, motion, &also, record);
      const StrainSweeps plain = plain_sweeps(springs, limited, start, inverse_mass, h, max_sweeps, plain_motion, plain_also);
      EXPECT_GT(plain.corrections, 20) << name << ", " << max_sweeps;  // the sweeps had work to do
      EXPECT_EQ(fast.corrections, plain.corrections) << name << ", " << max_sweeps;
      EXPECT_EQ(fast.work, plain.work) << name << ", " << max_sweeps;
      for (std::size_t v = 0; v < start.size(); ++v) {
        ASSERT_EQ(motion[v], plain_motion[v]) << name << ": vertex " << v << ", " << max_sweeps << " sweeps";
        ASSERT_EQ(also[v], plain_also[v]) << name << ": vertex " << v << ", " << max_sweeps << " sweeps";
      }
    }
  };
  // Many springs pass their limit, and the sweeps run long.
  std::vector<Vec3> everywhere;
  for (std::size_t v = 0; v < positions.size(); ++v) everywhere.emplace_back(speed(rng), speed(rng), speed(rng));
  check("random motion", positions, everywhere);
  // A few springs pass their limit and the sweeps' work spreads from them: blocks of springs
  // are passed over (STRAIN_BLOCK), and a correction must mark both its ends' blocks (this case
  // fails when it marks only one end's).
  std::vector<Vec3> flat = positions, few(positions.size(), Vec3::Zero());
  for (int v = 0; v < side * side; ++v) flat[std::size_t(v)] = Vec3(0.01 * (v % side), 0.01 * (v / side), 0);  // at rest
  for (int k = 0; k < 6; ++k) few[std::size_t(rng() % positions.size())] = 3 * Vec3(speed(rng), speed(rng), speed(rng));
  check("a few fast vertices", flat, few);
}
