// Strain limiting (Integrator::limit_strain, Integrator::past_limit): docs/materials.md.
#include <algorithm>
#include <chrono>

#include "drape/core/integrator.h"
#include "integrator_workspace.h"
#include "strain_limit.h"

namespace drape {

Scalar longest_allowed(const Spring& s, Scalar start) {
  const Scalar limit = s.limit * s.rest_length;
  return start > limit ? start - STRAIN_RECOVERY * (start - limit) : limit;
}

StrainSweeps limit_strain_sweeps(const StrainSweepInput& in, std::vector<Vec3>& motion, std::vector<Vec3>* also,
                                 StrainSweepRecord& record) {
  // Named copies, not a structured binding: clang 14 (the fuzzers' build) does not let a
  // lambda capture a structured binding.
  const auto springs = in.springs;
  const auto limited = in.limited;
  const auto positions = in.positions;
  const auto inverse_mass = in.inverse_mass;
  const Scalar h = in.h;
  const int max_sweeps = in.max_sweeps;
  const auto held = in.held;
  const auto weight = [&](std::size_t v) { return !held.empty() && held[v] ? HELD_WEIGHT * inverse_mass[v] : inverse_mass[v]; };
  // A spring is looked at again only once an end of it has moved since it was last looked at:
  // a curtain caught on a moving paddle ran its 200 sweeps over all 14,520 springs in every
  // call for the few dozen along its taut chains, 5.5 s of a 13.9 s frame. And a block of
  // STRAIN_BLOCK springs (in the sweeps' order) none of whose ends has moved since it was last
  // looked at is passed over whole: a knit hanging from a needle still read every one of its
  // 10,100 springs in each sweep of its limit's rounds for the few dozen around the tip.
  const std::size_t count = limited.size(), blocks = (count + STRAIN_BLOCK - 1) / STRAIN_BLOCK;
  // The lists below are the limited springs' ends': made again when those differ.
  const auto ends = [&](std::size_t l) {
    const Spring& s = springs[std::size_t(limited[l])];
    return std::array<int, 2>{s.i, s.j};
  };
  bool same = record.ends.size() == count && record.first.size() == positions.size() + 1;
  for (std::size_t l = 0; l < count && same; ++l) same = record.ends[l] == ends(l);
  if (!same) {
    // Per vertex, the blocks holding its springs, in order: at[first[v]] ...
    std::vector<std::vector<int>> of(positions.size());
    record.ends.resize(count);
    for (std::size_t l = 0; l < count; ++l) {
      record.ends[l] = ends(l);
      for (const int v : record.ends[l]) {
        auto& list = of[std::size_t(v)];
        if (list.empty() || list.back() != int(l / STRAIN_BLOCK)) list.push_back(int(l / STRAIN_BLOCK));
      }
    }
    record.first.assign(1, 0);
    record.at.clear();
    for (const auto& list : of) record.at.insert(record.at.end(), list.begin(), list.end()), record.first.push_back(int(record.at.size()));
  }
  StrainSweeps done;
  record.changed.assign(positions.size(), -1);
  record.checked.assign(count, -2);
  record.block_changed.assign(blocks, -1);
  record.block_checked.assign(blocks, -2);
  // The longest each may end, from its length at the start (fixed through the sweeps).
  record.longest.resize(count);
  for (std::size_t l = 0; l < count; ++l) {
    const Spring& s = springs[std::size_t(limited[l])];
    record.longest[l] = longest_allowed(s, (positions[std::size_t(s.i)] - positions[std::size_t(s.j)]).norm());
  }
  for (int sweep = 0; sweep < max_sweeps; ++sweep) {
    bool passed = false;
    for (std::size_t b = 0; b < blocks; ++b) {
      if (record.block_changed[b] <= record.block_checked[b]) continue;
      record.block_checked[b] = done.corrections;
      for (std::size_t l = b * STRAIN_BLOCK; l < std::min(count, (b + 1) * STRAIN_BLOCK); ++l) {
        const Spring& s = springs[std::size_t(limited[l])];
        const auto i = std::size_t(s.i), j = std::size_t(s.j);
        if (record.changed[i] <= record.checked[l] && record.changed[j] <= record.checked[l]) continue;
        record.checked[l] = done.corrections;
        const Vec3 d = positions[i] + h * motion[i] - positions[j] - h * motion[j];
        // A spring the response left past its limit is pulled back by STRAIN_RECOVERY of its
        // excess: not all at once (its excess over h as a speed), nor none (a ratchet).
        const Scalar length = d.norm(), longest = record.longest[l];
        if (!(length > longest)) continue;
        const Scalar wi = weight(i), wj = weight(j);
        if (!(wi + wj > 0)) continue;  // both ends pinned: their handles decide
        // The ends' relative velocity along the spring less what brings it back to its limit.
        const Vec3 change = ((length - longest) / (h * (wi + wj) * length)) * d;
        motion[i] -= wi * change;
        motion[j] += wj * change;
        if (also) (*also)[i] -= wi * change, (*also)[j] += wj * change;
        // A pinned end's handle does work through the spring: the impulse it gives the free
        // end, against the handle's velocity (for the energy ledger).
        if (inverse_mass[i] == 0) done.work += std::max<Scalar>(0, change.dot(motion[i]));
        if (inverse_mass[j] == 0) done.work += std::max<Scalar>(0, -change.dot(motion[j]));
        ++done.corrections;
        record.changed[i] = record.changed[j] = done.corrections;
        for (const std::size_t v : {i, j})
          for (int k = record.first[v]; k < record.first[v + 1]; ++k) record.block_changed[std::size_t(record.at[std::size_t(k)])] = done.corrections;
        passed = true;
      }
    }
    if (!passed) break;
  }
  return done;
}

Scalar Integrator::limit_strain(const std::vector<Vec3>& positions, std::vector<Vec3>& motion, std::vector<Vec3>* also,
                                StepReport& report, std::span<const char> held) {
  Workspace& w = *work_;
  const auto begin = std::chrono::steady_clock::now();
  const StrainSweeps done = limit_strain_sweeps({model_.springs, w.limited_springs, positions, w.inverse_mass, h_, STRAIN_LIMIT_SWEEPS, held},
                                                motion, also, w.strain_sweeps);
  report.strain_limited += done.corrections;
  report.strain_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
  return done.work;
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
