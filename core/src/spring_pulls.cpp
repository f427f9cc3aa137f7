// The projective solver's spring pass (spring_pulls.h), written once against Google Highway:
// foreach_target.h compiles this file once per instruction set, HWY_EXPORT tables the kernel
// and HWY_DYNAMIC_DISPATCH calls the best one the machine runs. Every operation is the scalar
// formula's (projective.cpp, evaluate) on the same operands in the same order: -ffp-contract=off
// and no MulAdd, the 3-term sums as (a + b) + c like Eigen's for a Vec3 on its vectorised path
// (spring_pulls.h).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "spring_pulls.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "spring_pulls.h"

HWY_BEFORE_NAMESPACE();
namespace drape::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

void SpringPulls(const SpringPullInput& in, const SpringPullOutput& out) {
  const hn::CappedTag<double, SPRING_LANES> d;
  const std::size_t lanes = hn::Lanes(d);
  const auto zero = hn::Zero(d), one = hn::Set(d, 1.0), half = hn::Set(d, 0.5);
  for (std::size_t k = 0; k < in.count; k += lanes) {
    const auto zx = hn::LoadU(d, in.zx + k), zy = hn::LoadU(d, in.zy + k), zz = hn::LoadU(d, in.zz + k);
    const auto d0x = hn::LoadU(d, in.d0x + k), d0y = hn::LoadU(d, in.d0y + k), d0z = hn::LoadU(d, in.d0z + k);
    // |z| and the direction: z (1 / |z|), or the start's for a spring of zero length.
    const auto length = hn::Sqrt(hn::Add(hn::Add(hn::Mul(zx, zx), hn::Mul(zy, zy)), hn::Mul(zz, zz)));
    const auto inverse = hn::Div(one, length);
    const auto nonzero = hn::Gt(length, zero);
    const auto dx = hn::IfThenElse(nonzero, hn::Mul(zx, inverse), d0x);
    const auto dy = hn::IfThenElse(nonzero, hn::Mul(zy, inverse), d0y);
    const auto dz = hn::IfThenElse(nonzero, hn::Mul(zz, inverse), d0z);
    // The change of z along the start's direction: (z - z0) . d0.
    const auto along = hn::Add(hn::Add(hn::Mul(hn::Sub(zx, hn::LoadU(d, in.sx + k)), d0x),
                                       hn::Mul(hn::Sub(zy, hn::LoadU(d, in.sy + k)), d0y)),
                               hn::Mul(hn::Sub(zz, hn::LoadU(d, in.sz + k)), d0z));
    const auto elastic = hn::LoadU(d, in.elastic + k), viscous = hn::LoadU(d, in.viscous + k);
    const auto extension = hn::Sub(length, hn::LoadU(d, in.rest + k));
    const auto stretch = hn::Mul(elastic, extension), damp = hn::Mul(viscous, along);
    hn::StoreU(hn::Add(hn::Mul(stretch, dx), hn::Mul(damp, d0x)), d, out.px + k);
    hn::StoreU(hn::Add(hn::Mul(stretch, dy), hn::Mul(damp, d0y)), d, out.py + k);
    hn::StoreU(hn::Add(hn::Mul(stretch, dz), hn::Mul(damp, d0z)), d, out.pz + k);
    hn::StoreU(hn::Add(hn::Mul(hn::Mul(hn::Mul(half, elastic), extension), extension),
                       hn::Mul(hn::Mul(hn::Mul(half, viscous), along), along)),
               d, out.energy + k);
  }
}

}  // namespace drape::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace drape {
HWY_EXPORT(SpringPulls);

void spring_pulls(const SpringPullInput& in, const SpringPullOutput& out) { HWY_DYNAMIC_DISPATCH(SpringPulls)(in, out); }

std::vector<std::int64_t> spring_pull_targets() { return hwy::SupportedAndGeneratedTargets(); }

}  // namespace drape
#endif  // HWY_ONCE
