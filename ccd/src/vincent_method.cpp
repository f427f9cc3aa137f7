// The vincent method: sign variations V of the Bernstein coefficients on an interval. V = 0: no
// root; V = 1: exactly one, refined inside its bracket; V >= 2: split at the midpoint
// (Vincent's theorem: splitting ends with V <= 1 unless there is a multiple root). Before any
// root, the separation stage. ccd-notes.md sections 2-3.
#include <algorithm>

#include "methods.h"
#include "root_refinement.h"

namespace drape::ccd::detail {

Result vincent_method(const Problem& p) {
  const Bernstein3& b = p.cubic.b;
  switch (vincent_entry(p.cubic)) {
    case VincentEntry::Degenerate: return degenerate_path(p);
    case VincentEntry::Culled: return Result{};
    case VincentEntry::Stage: break;
  }
  const int variations = sign_variations(b);
  // The separation stage: wherever the cubic may vanish, the features are apart. That covers
  // the ends too: a root within rounding of t = 0 or t = 1 lies in the first or last kept
  // interval, so the inside tests below would fail there as well.
  if (stage_separates(p, contact_distance(p.options, p.cubic))) {
    Result apart;
    apart.path = Path::Separated;
    return apart;
  }
  Result result;
  if (root_possible_at_start(p.cubic)) {  // the features may start coplanar
    result.path = Path::Solved;
    if (touching_at(p, 0.0, result)) return result;
  }
  if (variations == 0 && !root_possible_at_end(p.cubic)) return result;
  result.path = Path::Solved;
  if (variations == 1) {
    // The common case after the cull: one root, bracketed by the ends of the step.
    result.root_solves = 1;
    if (touching_at(p, refine_single_root<Scalar>(b, p.options.root_tolerance), result)) return result;
    if (root_possible_at_end(p.cubic)) touching_at(p, 1.0, result);
    return result;
  }

  struct Interval {
    Scalar lo, hi;
    Bernstein3 b;
    int depth;
  };
  constexpr int STACK_SIZE = 64;
  Interval stack[STACK_SIZE];
  int top = 0;
  stack[top++] = {0.0, 1.0, b, 0};
  result.path = Path::Solved;
  int solves = 0;
  const int max_depth = std::min(p.options.max_subdivision_depth, STACK_SIZE - 2);
  while (top > 0) {
    const Interval I = stack[--top];
    const int variations = sign_variations(I.b);
    const Scalar width = I.hi - I.lo;
    if (variations == 1) {
      ++solves;
      const Scalar s = refine_single_root<Scalar>(I.b, p.options.root_tolerance / width);
      if (touching_at(p, I.lo + s * width, result)) break;
    } else if (variations >= 2) {
      if (I.depth >= max_depth) {
        // A tangential (multiple) root does not separate: test where it sits.
        result.path = Path::Degenerate;
        if (touching_at(p, I.lo + 0.5 * width, result)) break;
      } else {
        ++solves;
        Bernstein3 left, right;
        split_half(I.b, left, right);
        const Scalar mid = I.lo + 0.5 * width;
        stack[top++] = {mid, I.hi, right, I.depth + 1};
        stack[top++] = {I.lo, mid, left, I.depth + 1};
        continue;
      }
    }
    if (I.b[3] == 0 && touching_at(p, I.hi, result)) break;  // a root exactly at the end
  }
  if (!result.hit && root_possible_at_end(p.cubic)) touching_at(p, 1.0, result);
  result.root_solves = static_cast<std::uint16_t>(std::min(solves, 65535));
  return result;
}

}  // namespace drape::ccd::detail
