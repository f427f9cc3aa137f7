// The conservative method at the extremes, against an exact reference: queries built to touch
// at a known time from dyadic numbers (so every coordinate, at every scale 2^-27 ~ 1e-8 to
// 2^27 ~ 1e8, is exact in double), the contact then verified in exact rational arithmetic
// (GMP) from the stored coordinates. Families: generic, motion within ulps of coplanar,
// parallel edges, touching at t = 0 and at t = 1. conservative must miss none. (Out-of-plane
// motion of k 2^-45 for coordinates below 1: about a hundred ulps, the least that keeps the
// construction exact in double.)
#include <gmpxx.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "drape/ccd/query.h"

using namespace drape;
using namespace drape::ccd;

namespace {

constexpr int QUERIES_PER_CASE = 2000;

enum class Family { Generic, NearCoplanar, Parallel, AtStart, AtEnd };
const char* name(Family f) {
  switch (f) {
    case Family::Generic: return "generic";
    case Family::NearCoplanar: return "near-coplanar";
    case Family::Parallel: return "parallel";
    case Family::AtStart: return "touch-at-0";
    case Family::AtEnd: return "touch-at-1";
  }
  return "?";
}

struct Built {
  Query query;
  mpq_class t;         // the time of contact
  mpq_class p0, p1;    // vertex-face: barycentric weights of face[1], face[2]; edge-edge: s, u
};

// Small dyadic numbers: integers in [-range, range] over 2^bits.
struct Dyadic {
  std::mt19937_64 rng;
  double next(int range, int bits) {
    return std::ldexp(double(std::uniform_int_distribution<int>(-range, range)(rng)), -bits);
  }
  Vec3 vec(int range, int bits) { return Vec3(next(range, bits), next(range, bits), next(range, bits)); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
};

Built build(QueryKind kind, Family family, Dyadic& d, int scale_exponent) {
  Built b;
  const int t_numerator = family == Family::AtStart ? 0 : family == Family::AtEnd ? 64 : d.integer(1, 63);
  const double t = t_numerator / 64.0;
  b.t = mpq_class(t_numerator, 64);
  std::array<Vec3, 4> contact;  // positions at the time of contact
  std::array<Vec3, 4> velocity;
  for (Vec3& v : velocity) v = d.vec(64, 6);
  if (kind == QueryKind::VertexFace) {
    for (int i = 1; i < 4; ++i) contact[i] = d.vec(64, 6);
    const int w1 = d.integer(0, 16), w2 = d.integer(0, 16 - w1);
    contact[0] = contact[1] + (w1 / 16.0) * (contact[2] - contact[1]) + (w2 / 16.0) * (contact[3] - contact[1]);
    b.p0 = mpq_class(w1, 16);
    b.p1 = mpq_class(w2, 16);
    if (family == Family::Parallel) velocity[0] = velocity[1];  // the vertex keeps to its edge's motion
  } else {
    const Vec3 meet = d.vec(64, 6);
    const Vec3 da = d.vec(64, 6);
    const Vec3 db = family == Family::Parallel ? da : d.vec(64, 6);
    const int sa = d.integer(0, 16), sb = d.integer(0, 16);
    contact = {meet - (sa / 16.0) * da, meet + (1 - sa / 16.0) * da, meet - (sb / 16.0) * db, meet + (1 - sb / 16.0) * db};
    b.p0 = mpq_class(sa, 16);
    b.p1 = mpq_class(sb, 16);
    if (family == Family::Parallel) velocity[3] = velocity[2] + (velocity[1] - velocity[0]);  // keep b parallel to a
  }
  if (family == Family::NearCoplanar) {
    // Everything in the plane z = c, moving in it, plus out-of-plane motion of about 100 ulps.
    const double plane = contact[1].z();
    for (int i = 0; i < 4; ++i) {
      contact[i].z() = plane;
      velocity[i].z() = std::ldexp(double(d.integer(-4, 4)), -45);  // exact: 51 bits below the plane's
    }
    if (kind == QueryKind::VertexFace) contact[0].z() = plane;
  }
  const double scale = std::ldexp(1.0, scale_exponent);
  for (int i = 0; i < 4; ++i) {
    b.query.start[i] = scale * (contact[i] - t * velocity[i]);
    b.query.end[i] = scale * (contact[i] + (1 - t) * velocity[i]);
  }
  b.t.canonicalize();  // GMP compares only canonical fractions correctly
  b.p0.canonicalize();
  b.p1.canonicalize();
  return b;
}

mpq_class exact(double x) { return mpq_class(x); }

// The exact reference: from the stored doubles, the positions at the contact time in rationals;
// the contact holds exactly (the point is the stated combination of the face's corners, or the
// two edges' stated points coincide).
bool touches_exactly(QueryKind kind, const Built& b) {
  std::array<std::array<mpq_class, 3>, 4> x;
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k)
      x[i][k] = exact(b.query.start[i][k]) + b.t * (exact(b.query.end[i][k]) - exact(b.query.start[i][k]));
  for (int k = 0; k < 3; ++k) {
    if (kind == QueryKind::VertexFace) {
      const mpq_class on_face = x[1][k] + b.p0 * (x[2][k] - x[1][k]) + b.p1 * (x[3][k] - x[1][k]);
      if (on_face != x[0][k]) return false;
    } else {
      const mpq_class on_a = x[0][k] + b.p0 * (x[1][k] - x[0][k]);
      const mpq_class on_b = x[2][k] + b.p1 * (x[3][k] - x[2][k]);
      if (on_a != on_b) return false;
    }
  }
  return b.t >= 0 && b.t <= 1 && b.p0 >= 0 && b.p1 >= 0 && (kind == QueryKind::EdgeEdge ? (b.p0 <= 1 && b.p1 <= 1) : b.p0 + b.p1 <= 1);
}

}  // namespace

TEST(ExactExtremes, ConservativeMissesNoExactContactAtAnyScale) {
  Dyadic d{std::mt19937_64(77)};
  for (QueryKind kind : {QueryKind::VertexFace, QueryKind::EdgeEdge}) {
    for (Family family : {Family::Generic, Family::NearCoplanar, Family::Parallel, Family::AtStart, Family::AtEnd}) {
      for (int exponent : {-27, 0, 27}) {
        int misses[4] = {0, 0, 0, 0};
        for (int i = 0; i < QUERIES_PER_CASE; ++i) {
          const Built b = build(kind, family, d, exponent);
          ASSERT_TRUE(touches_exactly(kind, b)) << "the generator must build exact contacts: " << kind_name(kind) << " "
                                                << name(family) << " 2^" << exponent << " #" << i << " t=" << b.t << " p=" << b.p0 << "," << b.p1;
          for (Method m : ALL_METHODS) {
            Options options;
            options.method = m;
            const Result r = elementary_ccd(kind, b.query, options);
            if (!r.hit) ++misses[int(m)];
            if (m == Method::Conservative && r.hit) {
              EXPECT_LE(r.toc, b.t.get_d() + 1e-12);  // never later than the contact
            }
            if (std::getenv("DRAPE_DEBUG_EXACT") && m == Method::Vincent && !r.hit) {
              Options c;
              c.method = Method::Cubic;
              const Result rc = elementary_ccd(kind, b.query, c);
              if (rc.hit) std::printf("cubic hit at %.17g, vincent missed (path %d, solves %d), true t %.17g\n", rc.toc, int(r.path), int(r.root_solves), b.t.get_d());
            }
          }
        }
        EXPECT_EQ(misses[int(Method::Conservative)], 0) << kind_name(kind) << " " << name(family) << " 2^" << exponent;
        std::printf("%-12s %-14s scale 2^%-4d misses of %d: cubic %d, dnf %d, vincent %d, conservative %d\n",
                    std::string(kind_name(kind)).c_str(), name(family), exponent, QUERIES_PER_CASE, misses[0], misses[1],
                    misses[2], misses[3]);
      }
    }
  }
}
