// The conservative method: never reports "no contact" for a contact.
//
// Earliest-first bisection of the step [0, 1]. An interval is dropped when
//  - the cubic is certainly nonzero on it: all its Bernstein coefficients exceed their error
//    bound (plus thickness * |e1 x e2|) in one sign; or
//  - the cubic is certainly monotone on it, so it can vanish only in a narrow window around one
//    root, and at that root the features are farther apart than the window lets them close; or
//  - the distance at its midpoint, less how much it can shrink over half the interval, exceeds
//    the thickness.
// An interval that survives to the time tolerance is a contact at its start. Double precision
// cannot tell a touch from a near miss of about 1e-15 of the coordinates; so, for exact contact
// (zero thickness), the interval is searched again in long double (64-bit mantissa) before a
// contact is reported; a cubic that double precision cannot resolve (coplanar motion) is
// searched in double only until the first undecided interval, and in long double from there.
// The same algorithm serves both precisions.
#include "methods.h"
#include "root_refinement.h"

namespace drape::ccd::detail {
namespace {

// Rounding of a distance evaluated at time t, in units of u times the largest coordinate:
// positions interpolated at t (3 roundings), differences, dot products and the square root of
// the closest-point formulas (about 10 more). 32 leaves a factor of two or more to spare.
constexpr Scalar DISTANCE_ERROR_FACTOR = 32.0;
// Rounding added by each de Casteljau level, in units of u times the largest coefficient.
constexpr Scalar SUBDIVISION_ERROR_FACTOR = 4.0;
// The root of the monotone window is refined to this fraction of the window's half-width.
constexpr Scalar WINDOW_ROOT_FRACTION = 1e-3;
// Extended-precision search of an undecided interval: extra bisection levels below it, and its
// interval budget (bounds the worst case, an exactly coplanar sliding motion).
constexpr int EXTENDED_EXTRA_LEVELS = 34;
constexpr int EXTENDED_MAX_INTERVALS = 256;
// A nearly coplanar motion's search in double, before the long-double one: its interval budget.
// The Erleben near misses (coplanar, 1e-11 to 1e-4 apart) take 100 to 200; a motion double
// cannot decide stops at its first undecided interval, or at worst after 512, before the
// long-double search.
constexpr int COPLANAR_DOUBLE_INTERVALS = 512;
constexpr int STACK_SIZE = 160;  // depth-first: at most one pending sibling per level

using Extended = long double;
// The extended search's bounds use Extended's own unit roundoff, and it decides what double
// cannot only where that is at least 2^11 times finer: x87's 64-bit mantissa (or IEEE quad's
// 113 bits). Where long double is just double (MSVC, 32-bit ARM, some PowerPC ABIs) the
// guarantee would silently weaken, so the build stops here instead.
static_assert(std::numeric_limits<Extended>::digits >= 64,
              "conservative needs a long double with at least a 64-bit mantissa (x87 extended or IEEE quad)");

template <class T>
using Coefficients = std::array<T, 4>;

// Bound on how fast the distance between the features can change over the step: the largest
// displacement of a point of one feature relative to a point of the other.
Scalar relative_speed_bound(QueryKind kind, const Query& q) {
  const auto d = [&](int i) -> Vec3 { return q.end[i] - q.start[i]; };
  Scalar speed = 0;
  if (kind == QueryKind::VertexFace) {
    for (int i = 1; i < 4; ++i) speed = std::max(speed, (d(0) - d(i)).norm());
  } else {
    for (int i = 0; i < 2; ++i)
      for (int j = 2; j < 4; ++j) speed = std::max(speed, (d(i) - d(j)).norm());
  }
  return speed * (1 + 8 * UNIT_ROUNDOFF);
}

// |d(t)| = (distance to the plane or between the lines) * |e1(t) x e2(t)|, with e1, e2 the
// triangle's edges from face[0] (vertex-face) or the two edges (edge-edge); the feature distance
// is at least that. |e1 x e2| <= |e1| |e2| and a linear |e(t)| is largest at an end of the step,
// so |d| > thickness * |e1|max |e2|max proves the features stay farther apart than thickness.
Scalar thickness_to_cubic(QueryKind kind, const Query& q, Scalar thickness) {
  if (thickness <= 0) return 0;
  const auto longest = [&](int i, int j) {
    return std::max((q.start[j] - q.start[i]).norm(), (q.end[j] - q.end[i]).norm());
  };
  const Scalar factor = kind == QueryKind::VertexFace ? longest(1, 2) * longest(1, 3) : longest(0, 1) * longest(2, 3);
  return thickness * factor * (1 + 16 * UNIT_ROUNDOFF);
}

// de Casteljau split at local parameter s.
template <class T>
void split_at(const Coefficients<T>& b, T s, Coefficients<T>& left, Coefficients<T>& right) {
  const T r = 1 - s;
  const T b01 = r * b[0] + s * b[1], b12 = r * b[1] + s * b[2], b23 = r * b[2] + s * b[3];
  const T b012 = r * b01 + s * b12, b123 = r * b12 + s * b23;
  const T mid = r * b012 + s * b123;
  left = {b[0], b01, b012, mid};
  right = {mid, b123, b23, b[3]};
}

// What a search in double does with an interval it cannot decide.
enum class Escalation {
  None,          // a contact at its start (long double, or a thickness: nothing finer to try)
  Interval,      // search that interval again in long double: a contact unless it is cleared
  RestOfStep,    // from its start, search the rest of the step in long double, which decides;
                 // the same when the budget runs out
};

// Extent of a long-double search.
enum class ExtendedSpan {
  Undecided,   // below an interval double precision left undecided: a fine time tolerance and
               // a small budget
  RestOfStep,  // [lo, 1] with the options' tolerance and budget
};

// What one search needs, in its precision.
template <class T>
struct Setup {
  const Problem& problem;
  bool use_cubic;
  T speed;            // relative speed bound
  T distance_margin;  // thickness plus the rounding of a distance
  T cubic_margin;     // rounding of the coefficients plus thickness * |e1 x e2|
  T level_error;      // rounding added by one subdivision level
  T time_tolerance;
  int max_intervals;
  Escalation escalation;
};

template <class T>
Setup<T> make_setup(const Problem& p, bool use_cubic, const Coefficients<T>& b, T cubic_error) {
  const Options& o = p.options;
  const T u = std::numeric_limits<T>::epsilon() / 2;
  return Setup<T>{p,
                  use_cubic,
                  T(relative_speed_bound(p.kind, p.query)),
                  T(o.thickness) + T(DISTANCE_ERROR_FACTOR) * u * T(max_abs_coordinate(p.query)),
                  cubic_error + T(thickness_to_cubic(p.kind, p.query, o.thickness)),
                  T(SUBDIVISION_ERROR_FACTOR) * u * max_abs(b),
                  T(o.time_tolerance),
                  o.max_intervals,
                  Escalation::None};
}

template <class T>
struct Interval {
  T lo, hi;
  Coefficients<T> b;
  int depth;  // subdivision levels below the coefficients' own computation
};

template <class T>
struct Outcome {
  bool hit = false;
  T toc = 1;
  Vec2 params = Vec2::Zero();
  bool budget_spent = false;
  bool culled = false;  // the whole interval excluded by the cubic at once
  int examined = 0;
};

// Whether [lo, hi] certainly holds no exact contact, searched in long double.
Outcome<Extended> extended_search(const Problem& p, bool use_cubic, Scalar lo, Scalar hi, ExtendedSpan span);

template <class T>
Outcome<T> search(const Setup<T>& setup, Interval<T> first) {
  const Problem& p = setup.problem;
  Interval<T> stack[STACK_SIZE];
  int top = 0;
  stack[top++] = first;
  Outcome<T> out;

  // The rest of the step from lo, searched in long double, decides.
  const auto rest_in_extended = [&](T lo) {
    const auto fine = extended_search(p, setup.use_cubic, Scalar(lo), 1.0, ExtendedSpan::RestOfStep);
    out.examined += fine.examined;
    out.hit = fine.hit;
    out.toc = T(fine.toc);
    out.params = fine.params;
    out.budget_spent = fine.budget_spent;
  };

  // An undecided interval: a contact (true: the search ends), unless its escalation clears it.
  const auto undecided = [&](const Interval<T>& I, T toc, Vec2 params) {
    if (setup.escalation == Escalation::RestOfStep) {
      rest_in_extended(I.lo);
      return true;
    }
    if (setup.escalation == Escalation::Interval) {
      const auto fine = extended_search(p, setup.use_cubic, Scalar(I.lo), Scalar(I.hi), ExtendedSpan::Undecided);
      out.examined += fine.examined;
      if (!fine.hit) return false;
      out.budget_spent = fine.budget_spent;
      toc = std::max(I.lo, T(fine.toc));
      params = fine.params;
    }
    out.hit = true;
    out.toc = toc;
    out.params = params;
    return true;
  };

  while (top > 0) {
    const Interval<T> I = stack[--top];
    ++out.examined;
    const T width = I.hi - I.lo;
    const T error = setup.cubic_margin + T(I.depth) * setup.level_error;
    if (setup.use_cubic && certainly_nonzero(I.b, error)) {
      out.culled = out.examined == 1;
      continue;
    }

    if (setup.use_cubic) {
      // Monotone on the interval: |d| <= error only within half_width (local units) of s.
      const std::array<T, 3> slope{3 * (I.b[1] - I.b[0]), 3 * (I.b[2] - I.b[1]), 3 * (I.b[3] - I.b[2])};
      const T slope_error = 6 * error + 8 * (std::numeric_limits<T>::epsilon() / 2) * max_abs(I.b);
      const bool rising = slope[0] > slope_error && slope[1] > slope_error && slope[2] > slope_error;
      const bool falling = slope[0] < -slope_error && slope[1] < -slope_error && slope[2] < -slope_error;
      if (rising || falling) {
        const T min_slope = std::min({std::abs(slope[0]), std::abs(slope[1]), std::abs(slope[2])}) - slope_error;
        const T half_width = error / min_slope;
        const T root_tolerance = T(WINDOW_ROOT_FRACTION) * half_width;
        T s = 0;
        if (I.b[0] == 0) s = 0;
        else if (I.b[3] == 0) s = 1;
        else if ((I.b[0] < 0) != (I.b[3] < 0)) s = refine_single_root<T>(I.b, root_tolerance);
        else s = std::abs(I.b[0]) <= std::abs(I.b[3]) ? T(0) : T(1);
        const T t = I.lo + s * width;
        const T reach = (half_width + root_tolerance) * width;  // in step units
        const auto prox = proximity_at<T>(p.kind, p.query, t);
        if (prox.distance - prox.error - setup.distance_margin > setup.speed * reach) continue;
        if (2 * reach <= setup.time_tolerance) {
          if (undecided(I, std::max(I.lo, t - reach), prox.params)) break;
          continue;
        }
      }
    }

    const T mid = I.lo + width / 2;
    const auto prox = proximity_at<T>(p.kind, p.query, mid);
    if (prox.distance - prox.error - setup.distance_margin > width / 2 * setup.speed) continue;
    if (out.examined >= setup.max_intervals || top + 2 > STACK_SIZE) {
      if (setup.escalation == Escalation::RestOfStep) {
        rest_in_extended(I.lo);
        break;
      }
      // Out of budget: a contact at the earliest time not yet excluded.
      out.budget_spent = true;
      out.hit = true;
      out.toc = I.lo;
      out.params = prox.params;
      break;
    }
    if (width <= setup.time_tolerance) {
      if (undecided(I, I.lo, prox.params)) break;
      continue;
    }
    Coefficients<T> left, right;
    split_at<T>(I.b, T(0.5), left, right);
    stack[top++] = {mid, I.hi, right, I.depth + 1};
    stack[top++] = {I.lo, mid, left, I.depth + 1};
  }
  return out;
}

Outcome<Extended> extended_search(const Problem& p, bool use_cubic, Scalar lo, Scalar hi, ExtendedSpan span) {
  using T = Extended;
  const auto cubic = coplanarity_cubic_in<T>(p.kind, p.query);
  // The coefficients on [lo, hi]: two splits, at lo and then at hi within [lo, 1].
  Coefficients<T> left, right = cubic.b;
  if (lo > 0) split_at<T>(cubic.b, T(lo), left, right);
  Coefficients<T> on_interval = right;
  if (hi < 1) split_at<T>(right, (T(hi) - T(lo)) / (1 - T(lo)), on_interval, left);
  Setup<T> setup = make_setup<T>(p, use_cubic, cubic.b, cubic.error);
  if ((lo > 0 || hi < 1) && span == ExtendedSpan::Undecided) {
    // Below an interval double precision left undecided.
    setup.time_tolerance = (T(hi) - T(lo)) * std::ldexp(T(1), -EXTENDED_EXTRA_LEVELS);
    setup.max_intervals = EXTENDED_MAX_INTERVALS;
  }
  return search<T>(setup, Interval<T>{T(lo), T(hi), on_interval, 2});
}

}  // namespace

// The two features' boxes over the whole step are farther apart than the thickness along
// some axis: no contact at any time. Exact but for the rounding of one subtraction.
bool swept_boxes_apart(const Problem& p) {
  const Query& q = p.query;
  const int split = p.kind == QueryKind::VertexFace ? 1 : 2;  // points [0, split) vs [split, 4)
  Vec3 lo_a = q.start[0], hi_a = q.start[0], lo_b = q.start[split], hi_b = q.start[split];
  for (int i = 0; i < 4; ++i) {
    Vec3& lo = i < split ? lo_a : lo_b;
    Vec3& hi = i < split ? hi_a : hi_b;
    lo = lo.cwiseMin(q.start[i]).cwiseMin(q.end[i]);
    hi = hi.cwiseMax(q.start[i]).cwiseMax(q.end[i]);
  }
  const Scalar gap = std::max((lo_b - hi_a).maxCoeff(), (lo_a - hi_b).maxCoeff());
  return gap > p.options.thickness + 4 * UNIT_ROUNDOFF * max_abs_coordinate(q);
}

Result conservative_search(const Problem& p, bool use_cubic) {
  // The degenerate path's cheap first question (a flat cloth sends most of its tests here).
  if (!use_cubic && swept_boxes_apart(p)) {
    Result apart;
    apart.path = Path::Solved;
    return apart;
  }
  // The search's first question, before the search is set up (most tests of a cloth step end
  // here): the cubic, off by at most its error, stays farther from zero than the thickness lets
  // it come over the whole step.
  const Scalar thickness_share = use_cubic ? thickness_to_cubic(p.kind, p.query, p.options.thickness) : 0;
  const ConservativeEntry entry = use_cubic ? conservative_entry(p.cubic, thickness_share) : ConservativeEntry::Search;
  if (entry == ConservativeEntry::Culled) {
    Result culled;
    culled.path = Path::Culled;
    culled.root_solves = 1;  // one interval examined, as the search counts it
    return culled;
  }
  // Only the conservative method itself escalates to long double; the degenerate path of the
  // other methods (use_cubic = false) stays in double.
  const bool exact_contact = p.options.thickness == 0 && use_cubic;
  // The filter's separation stage. A contact is a time where the features are at most the
  // thickness apart, so where |d| <= thickness |e1| |e2| (thickness_to_cubic; d = 0 for exact
  // contact). roots_apart keeps every sub-interval where the cubic, off by at most twice its
  // error, may come that close to zero, and shows the features farther apart than the
  // thickness (plus the rounding of the positions) over each.
  if (entry == ConservativeEntry::Stage && stage_separates(p, p.options.thickness, thickness_share)) {
    Result apart;
    apart.path = Path::Separated;
    return apart;
  }
  Outcome<Scalar> out;
  if (exact_contact && cubic_poorly_resolved(p.cubic)) {
    // Coplanar, or nearly, to double precision. The cubic in long double (rounding error 2^11
    // times smaller) may still exclude the whole step. If not, a search in double excludes
    // what it can by distance (its error, about 1e-15 of the coordinates, is far below the gaps
    // of most such motions), earliest first, within a small budget; from the first interval it
    // cannot decide, the rest of the step is searched in long double, where an interval costs
    // several double ones.
    const auto fine_cubic = coplanarity_cubic_in<Extended>(p.kind, p.query);
    if (certainly_nonzero(fine_cubic.b, fine_cubic.error)) {
      out.culled = true;
      out.examined = 1;
    } else {
      Setup<Scalar> setup = make_setup<Scalar>(p, use_cubic, p.cubic.b, p.cubic.error);
      setup.max_intervals = std::min(setup.max_intervals, COPLANAR_DOUBLE_INTERVALS);
      setup.escalation = Escalation::RestOfStep;
      out = search<Scalar>(setup, Interval<Scalar>{0.0, 1.0, p.cubic.b, 0});
    }
  } else {
    Setup<Scalar> setup = make_setup<Scalar>(p, use_cubic, p.cubic.b, p.cubic.error);
    setup.escalation = exact_contact ? Escalation::Interval : Escalation::None;
    out = search<Scalar>(setup, Interval<Scalar>{0.0, 1.0, p.cubic.b, 0});
  }
  Result result;
  result.hit = out.hit;
  result.toc = out.hit ? out.toc : 1.0;
  result.params = out.params;
  result.path = out.budget_spent ? Path::Degenerate : (out.culled ? Path::Culled : Path::Solved);
  result.root_solves = static_cast<std::uint16_t>(std::min(out.examined, 65535));
  return result;
}

}  // namespace drape::ccd::detail
