// The degenerate families (degenerate_families.h). Positions are built at the moment of
// degeneracy from a line P + lambda D, then moved linearly with dyadic velocities; every number
// is an integer over a power of two of at most 2^-12 (2^-36 for the Beside offset), at most
// 2^8 in size, so every coordinate is exact in double before and after the scaling.
#include "drape/ccd_eval/degenerate_families.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace drape::ccd {
namespace {

// Offset of a Beside placement from the degenerate feature: 2^-36 of the scale.
constexpr int BESIDE_EXPONENT = -36;

struct Dyadic {
  std::mt19937_64 rng;
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
  double next(int range, int bits) { return std::ldexp(double(integer(-range, range)), -bits); }
  Vec3 vec(int range, int bits) { return Vec3(next(range, bits), next(range, bits), next(range, bits)); }
  Vec3 nonzero_vec(int range, int bits) {
    Vec3 v;
    do v = vec(range, bits);
    while (v == Vec3::Zero());
    return v;
  }
  bool coin() { return integer(0, 1) == 1; }
};

// A moving line P(t) + lambda D(t): its point at lambda at the start and at the end.
struct Line {
  Vec3 p0, d0, p1, d1;
  Vec3 at_start(double lambda) const { return p0 + lambda * d0; }
  Vec3 at_end(double lambda) const { return p1 + lambda * d1; }
};

// Parameters (multiples of 1/8) of the degenerate feature's points along the line, and of the
// other feature's placed point.
struct Layout {
  std::vector<double> feature;  // the degenerate feature's points (3 corners, or 1 or 2 ends)
  std::vector<double> other;    // the other feature's points on the line (1 or 2)
  bool beside = false;          // the other feature is moved off the line by 2^-36
};

double eighth(Dyadic& d, int lo, int hi) { return d.integer(lo, hi) / 8.0; }

// A parameter strictly inside (lo, hi), a multiple of 1/64.
double inside(Dyadic& d, double lo, double hi) { return lo + (hi - lo) * d.integer(1, 7) / 8.0; }

Layout layout(const DegenerateCase& c, Dyadic& d) {
  Layout l;
  const bool point_feature = c.shape == DegenerateShape::ThreeCornersMeet || c.shape == DegenerateShape::TwoZeroLengthEdges;
  // The degenerate feature.
  switch (c.shape) {
    case DegenerateShape::CollinearTriangle: {
      double a = eighth(d, -48, 48), b, m;
      do b = eighth(d, -48, 48);
      while (std::abs(b - a) < 0.25);
      m = inside(d, std::min(a, b), std::max(a, b));
      l.feature = {a, b, m};
      break;
    }
    case DegenerateShape::TwoCornersMeet: {
      double a = eighth(d, -48, 48), b;
      do b = eighth(d, -48, 48);
      while (std::abs(b - a) < 0.25);
      l.feature = {a, a, b};
      break;
    }
    case DegenerateShape::ThreeCornersMeet: {
      const double a = eighth(d, -48, 48);
      l.feature = {a, a, a};
      break;
    }
    case DegenerateShape::TwoZeroLengthEdges: l.feature = {eighth(d, -48, 48)}; break;
    case DegenerateShape::ZeroLengthEdge:  // the segment the zero-length edge is placed against
    case DegenerateShape::CollinearEdges: {
      double a = eighth(d, -48, 48), b;
      do b = eighth(d, -48, 48);
      while (std::abs(b - a) < 0.25);
      l.feature = {a, b};
      break;
    }
  }
  std::shuffle(l.feature.begin(), l.feature.end(), d.rng);
  const double lo = *std::min_element(l.feature.begin(), l.feature.end());
  const double hi = *std::max_element(l.feature.begin(), l.feature.end());
  const double length = std::max(hi - lo, 1.0);
  // The other feature: a point (vertex-face; edge-edge with a zero-length edge), the other
  // zero-length edge, or the other collinear edge.
  const bool other_is_segment = c.shape == DegenerateShape::CollinearEdges;
  const auto point_at = [&](DegeneratePlacement p) -> double {
    switch (p) {
      case DegeneratePlacement::Interior:
      case DegeneratePlacement::Beside:
        if (point_feature) return lo;
        // A collinear triangle's middle corner a quarter of the time, else inside the segment.
        if (l.feature.size() == 3 && d.integer(0, 3) == 0) return l.feature[0] + l.feature[1] + l.feature[2] - lo - hi;
        return inside(d, lo, hi);
      case DegeneratePlacement::Boundary: return d.coin() ? lo : hi;
      case DegeneratePlacement::Extension: {
        const double gap = length * d.integer(1, 16) / 8.0;
        return d.coin() ? lo - gap : hi + gap;
      }
    }
    return lo;
  };
  if (!other_is_segment) {
    l.other = {point_at(c.placement)};
  } else {
    // The other collinear edge: overlapping the first's interior, touching it at an end, apart
    // from it along the line, or overlapping but beside the line.
    const double span = length * d.integer(2, 16) / 8.0;
    switch (c.placement) {
      case DegeneratePlacement::Interior:
      case DegeneratePlacement::Beside: {
        const double from = inside(d, lo, hi);
        l.other = {from, d.coin() ? from + span : from - span};
        break;
      }
      case DegeneratePlacement::Boundary: l.other = d.coin() ? std::vector<double>{hi, hi + span} : std::vector<double>{lo - span, lo}; break;
      case DegeneratePlacement::Extension: {
        const double gap = length * d.integer(1, 16) / 8.0;
        l.other = d.coin() ? std::vector<double>{hi + gap, hi + gap + span} : std::vector<double>{lo - gap - span, lo - gap};
        break;
      }
    }
    std::shuffle(l.other.begin(), l.other.end(), d.rng);
  }
  l.beside = c.placement == DegeneratePlacement::Beside;
  return l;
}

Query build(const DegenerateCase& c, Dyadic& d, int scale_exponent) {
  Layout l = layout(c, d);
  // ZeroLengthEdge's layout holds the point in other and the segment in feature; its degenerate
  // edge is the point: both of its ends at the one parameter.
  std::vector<double> first, second;  // the query's first feature's points, then the second's
  if (c.kind == QueryKind::VertexFace) {
    first = l.other;  // the vertex
    second = l.feature;
  } else if (c.shape == DegenerateShape::ZeroLengthEdge) {
    first = {l.other[0], l.other[0]};
    second = l.feature;
  } else if (c.shape == DegenerateShape::TwoZeroLengthEdges) {
    first = {l.feature[0], l.feature[0]};
    second = {l.other[0], l.other[0]};
  } else {
    first = l.feature;
    second = l.other;
  }
  // The other feature's offset from the line (Beside).
  const Vec3 offset = l.beside ? Vec3(std::ldexp(1.0, BESIDE_EXPONENT) * d.nonzero_vec(8, 0)) : Vec3(Vec3::Zero());
  const bool offset_first = c.kind == QueryKind::VertexFace;  // the vertex, or the second edge
  Query q;
  const int t_numerator = c.when == DegenerateWhen::AtStart ? 0 : c.when == DegenerateWhen::AtEnd ? 64 : d.integer(1, 63);
  const double t = t_numerator / 64.0;
  std::array<double, 4> lambda{};
  for (int i = 0; i < 4; ++i) lambda[std::size_t(i)] = i < int(first.size()) ? first[std::size_t(i)] : second[std::size_t(i - int(first.size()))];
  const auto offset_of = [&](int i) { return (offset_first ? i < int(first.size()) : i >= int(first.size())) ? offset : Vec3::Zero(); };
  if (c.when == DegenerateWhen::Throughout) {
    // Every point on the moving line for the whole step, at a fixed parameter.
    Line line{d.vec(64, 4), d.nonzero_vec(8, 2), d.vec(64, 4), d.nonzero_vec(8, 2)};
    for (int i = 0; i < 4; ++i) {
      q.start[std::size_t(i)] = line.at_start(lambda[std::size_t(i)]) + offset_of(i);
      q.end[std::size_t(i)] = line.at_end(lambda[std::size_t(i)]) + offset_of(i);
    }
  } else {
    // The configuration at time t, every point moving with its own velocity.
    const Vec3 p = d.vec(64, 4), direction = d.nonzero_vec(8, 2);
    for (int i = 0; i < 4; ++i) {
      const Vec3 at_t = p + lambda[std::size_t(i)] * direction + offset_of(i);
      const Vec3 velocity = d.vec(64, 6);
      q.start[std::size_t(i)] = at_t - t * velocity;
      q.end[std::size_t(i)] = at_t + (1 - t) * velocity;
    }
  }
  for (int i = 0; i < 4; ++i) {
    q.start[std::size_t(i)] = q.start[std::size_t(i)].unaryExpr([&](double v) { return std::ldexp(v, scale_exponent); });
    q.end[std::size_t(i)] = q.end[std::size_t(i)].unaryExpr([&](double v) { return std::ldexp(v, scale_exponent); });
  }
  return q;
}

const char* shape_name(DegenerateShape s) {
  switch (s) {
    case DegenerateShape::CollinearTriangle: return "collinear-triangle";
    case DegenerateShape::TwoCornersMeet: return "two-corners-meet";
    case DegenerateShape::ThreeCornersMeet: return "three-corners-meet";
    case DegenerateShape::ZeroLengthEdge: return "zero-length-edge";
    case DegenerateShape::TwoZeroLengthEdges: return "two-zero-length-edges";
    case DegenerateShape::CollinearEdges: return "collinear-edges";
  }
  return "?";
}

const char* when_name(DegenerateWhen w) {
  switch (w) {
    case DegenerateWhen::AtStart: return "at-start";
    case DegenerateWhen::AtEnd: return "at-end";
    case DegenerateWhen::Midstep: return "midstep";
    case DegenerateWhen::Throughout: return "throughout";
  }
  return "?";
}

const char* placement_name(DegeneratePlacement p) {
  switch (p) {
    case DegeneratePlacement::Interior: return "interior";
    case DegeneratePlacement::Boundary: return "boundary";
    case DegeneratePlacement::Extension: return "extension";
    case DegeneratePlacement::Beside: return "beside";
  }
  return "?";
}

}  // namespace

std::vector<DegenerateCase> degenerate_cases() {
  std::vector<DegenerateCase> out;
  constexpr DegenerateShape SHAPES[] = {DegenerateShape::CollinearTriangle, DegenerateShape::TwoCornersMeet,
                                        DegenerateShape::ThreeCornersMeet,  DegenerateShape::ZeroLengthEdge,
                                        DegenerateShape::TwoZeroLengthEdges, DegenerateShape::CollinearEdges};
  constexpr DegenerateWhen WHENS[] = {DegenerateWhen::AtStart, DegenerateWhen::AtEnd, DegenerateWhen::Midstep,
                                      DegenerateWhen::Throughout};
  constexpr DegeneratePlacement PLACEMENTS[] = {DegeneratePlacement::Interior, DegeneratePlacement::Boundary,
                                                DegeneratePlacement::Extension, DegeneratePlacement::Beside};
  for (const DegenerateShape shape : SHAPES) {
    const bool vertex_face = shape == DegenerateShape::CollinearTriangle || shape == DegenerateShape::TwoCornersMeet ||
                             shape == DegenerateShape::ThreeCornersMeet;
    // A point has no interior apart from itself (its boundary).
    const bool point = shape == DegenerateShape::ThreeCornersMeet || shape == DegenerateShape::TwoZeroLengthEdges;
    for (const DegenerateWhen when : WHENS)
      for (const DegeneratePlacement placement : PLACEMENTS) {
        if (point && placement == DegeneratePlacement::Interior) continue;
        out.push_back({vertex_face ? QueryKind::VertexFace : QueryKind::EdgeEdge, shape, when, placement});
      }
  }
  return out;
}

std::string describe(const DegenerateCase& c) {
  return std::string(kind_name(c.kind)) + " " + shape_name(c.shape) + " " + when_name(c.when) + " " +
         placement_name(c.placement);
}

std::vector<Query> generate_degenerate_queries(const DegenerateCase& c, std::size_t count, std::uint64_t seed,
                                               int scale_exponent) {
  Dyadic d{std::mt19937_64(seed)};
  std::vector<Query> out;
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) out.push_back(build(c, d, scale_exponent));
  return out;
}

}  // namespace drape::ccd
