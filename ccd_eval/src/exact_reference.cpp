// The exact reference (exact_reference.h): polynomials in t over the rationals, their real roots
// in [0, 1] isolated by Bernstein subdivision, and signs evaluated exactly at those roots.
#include "drape/ccd_eval/exact_reference.h"

#include <gmpxx.h>

#include <vector>

namespace drape::ccd {
namespace {

using Rational = mpq_class;
/// Coefficients of t^0, t^1, ...; empty for the zero polynomial (trimmed: no trailing zeros).
using Poly = std::vector<Rational>;

void trim(Poly& p) {
  while (!p.empty() && sgn(p.back()) == 0) p.pop_back();
}

int degree(const Poly& p) { return int(p.size()) - 1; }

Poly sub(const Poly& a, const Poly& b) {
  Poly r(std::max(a.size(), b.size()));
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (i < a.size()) r[i] += a[i];
    if (i < b.size()) r[i] -= b[i];
  }
  trim(r);
  return r;
}

Poly add(const Poly& a, const Poly& b) {
  Poly r(std::max(a.size(), b.size()));
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (i < a.size()) r[i] += a[i];
    if (i < b.size()) r[i] += b[i];
  }
  trim(r);
  return r;
}

Poly mul(const Poly& a, const Poly& b) {
  if (a.empty() || b.empty()) return {};
  Poly r(a.size() + b.size() - 1);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
  trim(r);
  return r;
}

Rational eval(const Poly& p, const Rational& t) {
  Rational v = 0;
  for (std::size_t i = p.size(); i-- > 0;) v = v * t + p[i];
  return v;
}

int sign_of(const Poly& p, const Rational& t) { return sgn(eval(p, t)); }

Poly derivative(const Poly& p) {
  Poly r;
  for (std::size_t i = 1; i < p.size(); ++i) r.push_back(p[i] * int(i));
  trim(r);
  return r;
}

// Remainder and quotient of a divided by a nonzero b.
void divide(Poly a, const Poly& b, Poly& quotient, Poly& remainder) {
  quotient.assign(a.size() >= b.size() ? a.size() - b.size() + 1 : 0, Rational(0));
  while (!a.empty() && a.size() >= b.size()) {
    const std::size_t shift = a.size() - b.size();
    const Rational factor = a.back() / b.back();
    quotient[shift] = factor;
    for (std::size_t i = 0; i < b.size(); ++i) a[i + shift] -= factor * b[i];
    a.pop_back();  // the leading term cancels exactly
    trim(a);
  }
  trim(quotient);
  remainder = a;
}

// Monic greatest common divisor (Euclid); the zero polynomial when both are zero.
Poly gcd(Poly a, Poly b) {
  while (!b.empty()) {
    Poly q, r;
    divide(a, b, q, r);
    a = std::move(b);
    b = std::move(r);
  }
  if (!a.empty()) {
    const Rational lead = a.back();
    for (Rational& c : a) c /= lead;
  }
  return a;
}

// The square-free part: the same roots, each simple.
Poly square_free(const Poly& p) {
  const Poly g = gcd(p, derivative(p));
  if (degree(g) < 1) return p;
  Poly q, r;
  divide(p, g, q, r);
  return q;
}

// Bernstein coefficients of p (degree n) on [lo, hi]: p(lo + (hi - lo) s) in powers of s, then
// b_k = sum_{i <= k} C(k, i) / C(n, i) a_i.
std::vector<Rational> bernstein_on(const Poly& p, const Rational& lo, const Rational& hi) {
  const Poly shift{lo, hi - lo};
  Poly g;
  for (std::size_t i = p.size(); i-- > 0;) g = add(mul(g, shift), Poly{p[i]});
  const int n = degree(p);
  g.resize(std::size_t(n + 1), Rational(0));
  std::vector<mpz_class> binomial(std::size_t(n + 1));
  std::vector<Rational> b(std::size_t(n + 1), Rational(0));
  for (int k = 0; k <= n; ++k) {
    for (int i = 0; i <= k; ++i) {
      mpz_class c_ki, c_ni;
      mpz_bin_uiui(c_ki.get_mpz_t(), unsigned(k), unsigned(i));
      mpz_bin_uiui(c_ni.get_mpz_t(), unsigned(n), unsigned(i));
      b[std::size_t(k)] += Rational(c_ki, c_ni) * g[std::size_t(i)];
    }
  }
  return b;
}

int sign_variations(const std::vector<Rational>& b) {
  int variations = 0, last = 0;
  for (const Rational& c : b) {
    const int s = sgn(c);
    if (s == 0) continue;
    if (last != 0 && s != last) ++variations;
    last = s;
  }
  return variations;
}

// A real root of a square-free polynomial: exactly lo when exact, else the only root of f in
// the open interval (lo, hi), where f(lo) and f(hi) have opposite signs.
struct Root {
  Poly f;
  Rational lo, hi;
  bool exact = false;
};

// Every root of the square-free f in (lo, hi), f nonzero at both ends.
void isolate(const Poly& f, const Rational& lo, const Rational& hi, std::vector<Root>& out) {
  const int variations = sign_variations(bernstein_on(f, lo, hi));
  if (variations == 0) return;
  // Exactly one root inside (Descartes' rule in the Bernstein basis), and a sign change across
  // the interval for sign_at's halving; a root at an end (t = 0 or 1) is split away from.
  if (variations == 1 && sgn(eval(f, lo)) != 0 && sgn(eval(f, hi)) != 0) {
    out.push_back(Root{f, lo, hi, false});
    return;
  }
  const Rational mid = (lo + hi) / 2;
  isolate(f, lo, mid, out);
  if (sgn(eval(f, mid)) == 0) out.push_back(Root{f, mid, mid, true});
  isolate(f, mid, hi, out);
}

// Every real root of p in [0, 1] (none for a constant or zero p).
std::vector<Root> roots_in_step(const Poly& p) {
  std::vector<Root> out;
  if (degree(p) < 1) return out;
  const Poly f = square_free(p);
  const Rational zero = 0, one = 1;
  if (sgn(eval(f, zero)) == 0) out.push_back(Root{f, zero, zero, true});
  if (sgn(eval(f, one)) == 0) out.push_back(Root{f, one, one, true});
  // The open interval (0, 1).
  isolate(f, zero, one, out);
  return out;
}

// The sign of g at the root, exactly; the root's interval may be narrowed.
int sign_at(const Poly& g, Root& root) {
  if (g.empty()) return 0;
  if (root.exact) return sign_of(g, root.lo);
  // g vanishes there exactly when it shares that root with f: the common factor h (simple
  // roots only, as f is square-free) changes sign across the interval.
  const Poly h = gcd(root.f, g);
  if (degree(h) >= 1 && sign_of(h, root.lo) * sign_of(h, root.hi) < 0) return 0;
  const int sign_lo = sign_of(root.f, root.lo);
  while (true) {
    const auto b = bernstein_on(g, root.lo, root.hi);
    bool positive = true, negative = true;
    for (const Rational& c : b) positive = positive && sgn(c) > 0, negative = negative && sgn(c) < 0;
    if (positive) return 1;
    if (negative) return -1;
    const Rational mid = (root.lo + root.hi) / 2;
    const int s = sign_of(root.f, mid);
    if (s == 0) {
      root = Root{root.f, mid, mid, true};
      return sign_of(g, mid);
    }
    (s == sign_lo ? root.lo : root.hi) = mid;
  }
}

using Point = std::array<Poly, 3>;  // a moving point: each coordinate linear in t

Point moving_point(const Vec3& start, const Vec3& end) {
  Point x;
  for (int k = 0; k < 3; ++k) {
    x[std::size_t(k)] = Poly{Rational(start[k]), Rational(end[k]) - Rational(start[k])};
    trim(x[std::size_t(k)]);
  }
  return x;
}

Point difference(const Point& a, const Point& b) { return {sub(a[0], b[0]), sub(a[1], b[1]), sub(a[2], b[2])}; }

Poly triple_product(const Point& u, const Point& v, const Point& w) {
  const Poly c0 = sub(mul(u[1], v[2]), mul(u[2], v[1]));
  const Poly c1 = sub(mul(u[2], v[0]), mul(u[0], v[2]));
  const Poly c2 = sub(mul(u[0], v[1]), mul(u[1], v[0]));
  return add(add(mul(c0, w[0]), mul(c1, w[1])), mul(c2, w[2]));
}

// 2D orientation of (u, v, w) in the projection onto coordinates i and j.
Poly orientation(const Point& u, const Point& v, const Point& w, int i, int j) {
  const Point vu = difference(v, u), wu = difference(w, u);
  return sub(mul(vu[std::size_t(i)], wu[std::size_t(j)]), mul(vu[std::size_t(j)], wu[std::size_t(i)]));
}

constexpr int PROJECTIONS[3][2] = {{1, 2}, {2, 0}, {0, 1}};

// The polynomials whose signs decide contact, and the decision from their signs at one time.
struct Conditions {
  Poly coplanarity;
  std::vector<Poly> orientations;  // per projection: 3 (vertex-face) or 4 (edge-edge)
  std::vector<Poly> differences;   // per coordinate: (one feature's point - the other's)
  int per_projection = 0;
  int per_coordinate = 0;
  QueryKind kind = QueryKind::VertexFace;

  // Whether the features touch at the root (where the coplanarity cubic vanishes).
  bool hold(Root& t) {
    // Boxes first (cheapest): for each coordinate some difference >= 0 and some <= 0.
    for (int k = 0; k < 3; ++k) {
      bool some_nonnegative = false, some_nonpositive = false;
      for (int m = 0; m < per_coordinate; ++m) {
        const int s = sign_at(differences[std::size_t(k * per_coordinate + m)], t);
        some_nonnegative = some_nonnegative || s >= 0;
        some_nonpositive = some_nonpositive || s <= 0;
      }
      if (!some_nonnegative || !some_nonpositive) return false;
    }
    if (sign_at(coplanarity, t) != 0) return false;
    for (int p = 0; p < 3; ++p) {
      int s[4];
      for (int m = 0; m < per_projection; ++m) s[m] = sign_at(orientations[std::size_t(p * per_projection + m)], t);
      if (kind == QueryKind::VertexFace) {
        // The point in the (possibly degenerate) triangle: no two orientations of opposite sign.
        const bool positive = s[0] > 0 || s[1] > 0 || s[2] > 0;
        const bool negative = s[0] < 0 || s[1] < 0 || s[2] < 0;
        if (positive && negative) return false;
      } else {
        // The segments meet: neither one's ends strictly on one side of the other's line.
        if (s[0] * s[1] > 0 || s[2] * s[3] > 0) return false;
      }
    }
    return true;
  }
};

Conditions conditions_of(QueryKind kind, const Query& q) {
  std::array<Point, 4> x;
  for (int i = 0; i < 4; ++i) x[std::size_t(i)] = moving_point(q.start[std::size_t(i)], q.end[std::size_t(i)]);
  Conditions c;
  c.kind = kind;
  // Points of the query, and which of them each 2D orientation takes (u, v, w): vertex-face,
  // the vertex (0) against each edge of the face (1, 2, 3); edge-edge, each edge's ends
  // against the other edge. The coordinate differences: one feature's points minus the other's.
  const bool vertex_face = kind == QueryKind::VertexFace;
  static constexpr int VF_ORIENTATIONS[][3] = {{1, 2, 0}, {2, 3, 0}, {3, 1, 0}};
  static constexpr int EE_ORIENTATIONS[][3] = {{0, 1, 2}, {0, 1, 3}, {2, 3, 0}, {2, 3, 1}};
  const int split = vertex_face ? 1 : 2;  // points [0, split) are the first feature's
  c.coplanarity = vertex_face ? triple_product(difference(x[2], x[1]), difference(x[3], x[1]), difference(x[0], x[1]))
                              : triple_product(difference(x[1], x[0]), difference(x[3], x[2]), difference(x[2], x[0]));
  c.per_projection = vertex_face ? 3 : 4;
  for (const auto& ij : PROJECTIONS)
    for (int o = 0; o < c.per_projection; ++o) {
      const int* uvw = vertex_face ? VF_ORIENTATIONS[o] : EE_ORIENTATIONS[o];
      c.orientations.push_back(orientation(x[std::size_t(uvw[0])], x[std::size_t(uvw[1])], x[std::size_t(uvw[2])], ij[0], ij[1]));
    }
  c.per_coordinate = split * (4 - split);
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < split; ++i)
      for (int j = split; j < 4; ++j)
        c.differences.push_back(sub(x[std::size_t(j)][std::size_t(k)], x[std::size_t(i)][std::size_t(k)]));
  return c;
}

// The features' boxes over the whole step apart along a coordinate: no contact at any time.
// Comparisons of doubles are exact.
bool swept_boxes_apart(QueryKind kind, const Query& q) {
  const int split = kind == QueryKind::VertexFace ? 1 : 2;
  for (int k = 0; k < 3; ++k) {
    double lo[2] = {q.start[0][k], q.start[std::size_t(split)][k]}, hi[2] = {lo[0], lo[1]};
    for (int i = 0; i < 4; ++i) {
      const int side = i < split ? 0 : 1;
      for (const double v : {q.start[std::size_t(i)][k], q.end[std::size_t(i)][k]}) {
        lo[side] = std::min(lo[side], v);
        hi[side] = std::max(hi[side], v);
      }
    }
    if (hi[0] < lo[1] || hi[1] < lo[0]) return true;
  }
  return false;
}

}  // namespace

bool exact_contact(QueryKind kind, const Query& query) {
  if (swept_boxes_apart(kind, query)) return false;
  Conditions c = conditions_of(kind, query);
  // Candidate times: where the features touch, the coplanarity cubic vanishes; if it vanishes
  // identically, every boundary of the set of touching times is t = 0, t = 1 or a root of one
  // of the deciding polynomials.
  std::vector<Root> candidates;
  if (!c.coplanarity.empty()) {
    candidates = roots_in_step(c.coplanarity);
  } else {
    candidates.push_back(Root{Poly{}, Rational(0), Rational(0), true});
    candidates.push_back(Root{Poly{}, Rational(1), Rational(1), true});
    for (const auto* list : {&c.orientations, &c.differences})
      for (const Poly& p : *list)
        for (Root& r : roots_in_step(p)) candidates.push_back(std::move(r));
  }
  for (Root& t : candidates)
    if (c.hold(t)) return true;
  return false;
}

}  // namespace drape::ccd
