// Strain limiting (Integrator::limit_strain, Integrator::past_limit): docs/materials.md.
#include <algorithm>
#include <chrono>

#include "drape/core/integrator.h"
#include "integrator_workspace.h"

namespace drape {

namespace {

// The longest a limited spring may end a step whose start found it `start` long: its limit, or
// STRAIN_RECOVERY of its excess shorter when it started past it (the response may leave one).
Scalar longest_allowed(const Spring& s, Scalar start) {
  const Scalar limit = s.limit * s.rest_length;
  return start > limit ? start - STRAIN_RECOVERY * (start - limit) : limit;
}

}  // namespace

Scalar Integrator::limit_strain(const std::vector<Vec3>& positions, std::vector<Vec3>& motion, std::vector<Vec3>* also,
                                StepReport& report) {
  const Model& m = model_;
  const Workspace& w = *work_;
  const Scalar h = h_;
  const auto begin = std::chrono::steady_clock::now();
  const auto inverse_mass = [&](int v) { return w.free_index[std::size_t(v)] >= 0 ? 1 / m.masses[std::size_t(v)] : 0.0; };
  Scalar work = 0;
  for (int sweep = 0; sweep < STRAIN_LIMIT_SWEEPS; ++sweep) {
    bool passed = false;
    for (int k : w.limited_springs) {
      const Spring& s = m.springs[std::size_t(k)];
      const Vec3 d = positions[s.i] + h * motion[s.i] - positions[s.j] - h * motion[s.j];
      // A spring the response left past its limit is pulled back by STRAIN_RECOVERY of its
      // excess: not all at once (its excess over h as a speed), nor none (a ratchet).
      const Scalar length = d.norm(), longest = longest_allowed(s, (positions[s.i] - positions[s.j]).norm());
      if (!(length > longest)) continue;
      const Scalar wi = inverse_mass(s.i), wj = inverse_mass(s.j);
      if (!(wi + wj > 0)) continue;  // both ends pinned: their handles decide
      // The ends' relative velocity along the spring less what brings it back to its limit.
      const Vec3 change = ((length - longest) / (h * (wi + wj) * length)) * d;
      motion[s.i] -= wi * change;
      motion[s.j] += wj * change;
      if (also) (*also)[s.i] -= wi * change, (*also)[s.j] += wj * change;
      // A pinned end's handle does work through the spring: the impulse it gives the free
      // end, against the handle's velocity (for the energy ledger).
      if (wi == 0) work += std::max<Scalar>(0, change.dot(motion[s.i]));
      if (wj == 0) work += std::max<Scalar>(0, -change.dot(motion[s.j]));
      ++report.strain_limited;
      passed = true;
    }
    if (!passed) break;
  }
  report.strain_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
  return work;
}

bool Integrator::past_limit(const std::vector<Vec3>& positions, const std::vector<Vec3>& motion) const {
  const Model& m = model_;
  for (int k : work_->limited_springs) {
    const Spring& s = m.springs[std::size_t(k)];
    const Scalar length = (positions[s.i] + h_ * motion[s.i] - positions[s.j] - h_ * motion[s.j]).norm();
    if (length > (1 + STRAIN_SLACK) * s.limit * s.rest_length) return true;
  }
  return false;
}

Scalar Integrator::limit_excess(const std::vector<Vec3>& start, const std::vector<Vec3>& end) const {
  const Model& m = model_;
  Scalar worst = 0;
  for (int k : work_->limited_springs) {
    const Spring& s = m.springs[std::size_t(k)];
    if (work_->free_index[s.i] < 0 && work_->free_index[s.j] < 0) continue;  // both ends pinned: their handles decide
    worst = std::max(worst, (end[s.i] - end[s.j]).norm() / longest_allowed(s, (start[s.i] - start[s.j]).norm()) - 1);
  }
  return worst;
}

}  // namespace drape
