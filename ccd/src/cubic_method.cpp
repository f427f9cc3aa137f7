// The cubic method: every real root of the coplanarity cubic by the closed form, the inside test
// at each in increasing order; and dnf, the same behind the filter's sign cull. ccd-notes.md
// section 1.
#include <array>

#include "drape/ccd/cubic_solver.h"
#include "methods.h"

namespace drape::ccd::detail {

Result cubic_method(const Problem& p) {
  if (cubic_poorly_resolved(p.cubic)) return degenerate_path(p);
  Result result;
  result.path = Path::Solved;
  result.root_solves = 1;
  if (root_possible_at_start(p.cubic) && touching_at(p, 0.0, result)) return result;
  std::array<Scalar, 3> roots{};
  const int count = solve_cubic(to_power(p.cubic.b), roots);
  for (int i = 0; i < count; ++i) {
    if (roots[i] < 0 || roots[i] > 1) continue;
    if (touching_at(p, roots[i], result)) return result;
  }
  if (root_possible_at_end(p.cubic)) touching_at(p, 1.0, result);
  return result;
}

Result dnf_method(const Problem& p) {
  // Unreliable roots first, as cubic does: the filter must not cull what cubic would find.
  // (The sign cull of a resolved cubic came first, in one_query or elementary_ccd.)
  if (cubic_poorly_resolved(p.cubic)) return degenerate_path(p);
  return cubic_method(p);
}

}  // namespace drape::ccd::detail
