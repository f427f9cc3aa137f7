#include "drape/ccd_eval/query_generator.h"

#include <random>

namespace drape::ccd {

const char* family_name(QueryFamily family) {
  switch (family) {
    case QueryFamily::Random: return "random";
    case QueryFamily::Contact: return "contact";
    case QueryFamily::CoplanarMotion: return "coplanar-motion";
    case QueryFamily::NearCoplanar: return "near-coplanar";
    case QueryFamily::ParallelEdges: return "parallel";
    case QueryFamily::TouchAtStart: return "touch-at-start";
    case QueryFamily::TouchAtEnd: return "touch-at-end";
    case QueryFamily::TinyMotion: return "tiny-motion";
    case QueryFamily::FarFromOrigin: return "far-from-origin";
  }
  return "?";
}

namespace {

class Sampler {
 public:
  explicit Sampler(std::uint64_t seed) : engine_(seed) {}
  Scalar uniform(Scalar lo, Scalar hi) { return std::uniform_real_distribution<Scalar>(lo, hi)(engine_); }
  Vec3 in_box(Scalar half) { return Vec3(uniform(-half, half), uniform(-half, half), uniform(-half, half)); }
  Vec3 in_plane(Scalar half) { return Vec3(uniform(-half, half), uniform(-half, half), 0.0); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(engine_); }

 private:
  std::mt19937_64 engine_;
};

// Points at time t_contact placed so that the features touch: the vertex at a random point of
// the triangle, or the edges crossing at random parameters.
std::array<Vec3, 4> touching_points(Sampler& s, QueryKind kind) {
  std::array<Vec3, 4> x;
  if (kind == QueryKind::VertexFace) {
    for (int i = 1; i < 4; ++i) x[i] = s.in_box(1.0);
    Scalar w1 = s.uniform(0, 1), w2 = s.uniform(0, 1);
    if (w1 + w2 > 1) w1 = 1 - w1, w2 = 1 - w2;
    x[0] = x[1] + w1 * (x[2] - x[1]) + w2 * (x[3] - x[1]);
  } else {
    const Vec3 meet = s.in_box(1.0);
    const Vec3 da = s.in_box(1.0), db = s.in_box(1.0);
    const Scalar sa = s.uniform(0, 1), sb = s.uniform(0, 1);
    x[0] = meet - sa * da;
    x[1] = meet + (1 - sa) * da;
    x[2] = meet - sb * db;
    x[3] = meet + (1 - sb) * db;
  }
  return x;
}

Query moving_through(const std::array<Vec3, 4>& at_contact, Scalar t_contact, Sampler& s, Scalar speed) {
  Query q;
  for (int i = 0; i < 4; ++i) {
    const Vec3 v = s.in_box(speed);
    q.start[i] = at_contact[i] - t_contact * v;
    q.end[i] = at_contact[i] + (1 - t_contact) * v;
  }
  return q;
}

Query one_query(QueryFamily family, QueryKind kind, Sampler& s) {
  Query q;
  switch (family) {
    case QueryFamily::Random:
      for (int i = 0; i < 4; ++i) {
        q.start[i] = s.in_box(1.0);
        q.end[i] = q.start[i] + s.in_box(1.0);
      }
      return q;
    case QueryFamily::Contact:
      return moving_through(touching_points(s, kind), s.uniform(0, 1), s, 1.0);
    case QueryFamily::TouchAtStart:
      return moving_through(touching_points(s, kind), 0.0, s, 1.0);
    case QueryFamily::TouchAtEnd:
      return moving_through(touching_points(s, kind), 1.0, s, 1.0);
    case QueryFamily::TinyMotion:
      return moving_through(touching_points(s, kind), s.uniform(0, 1), s, 1e-10);
    case QueryFamily::FarFromOrigin: {
      q = moving_through(touching_points(s, kind), s.uniform(0, 1), s, 1.0);
      const Vec3 offset(1e6, -1e6, 1e6);
      for (int i = 0; i < 4; ++i) q.start[i] += offset, q.end[i] += offset;
      return q;
    }
    case QueryFamily::CoplanarMotion:
    case QueryFamily::NearCoplanar:
      for (int i = 0; i < 4; ++i) {
        q.start[i] = s.in_plane(1.0);
        q.end[i] = q.start[i] + s.in_plane(1.0);
      }
      if (family == QueryFamily::NearCoplanar)
        for (int i = 0; i < 4; ++i) q.end[i].z() = s.integer(-4, 4) * 1e-16, q.start[i].z() = s.integer(-4, 4) * 1e-16;
      return q;
    case QueryFamily::ParallelEdges: {
      // Both edges (or the vertex and one triangle edge) translate, keeping one direction. Every
      // other query is built to touch: collinear and overlapping at a random time t_c.
      const Vec3 direction = s.in_box(1.0);
      const Vec3 va = s.in_box(1.0), vb = s.in_box(1.0);
      const bool touching = s.integer(0, 1) == 1;
      const Scalar t_c = s.uniform(0, 1);
      const Vec3 a0 = s.in_box(1.0);
      const Vec3 a_at_contact = a0 + t_c * va;
      // The other feature's start: on edge a's line at t_c when touching, anywhere otherwise.
      const Scalar along = kind == QueryKind::EdgeEdge ? s.uniform(-0.5, 0.5) : s.uniform(0, 1);
      const Vec3 other0 = touching ? Vec3(a_at_contact + along * direction - t_c * vb) : s.in_box(1.0);
      if (kind == QueryKind::EdgeEdge) {
        const Scalar length_b = s.uniform(0.2, 2);
        q.start = {a0, a0 + direction, other0, other0 + length_b * direction};
        q.end = {a0 + va, a0 + va + direction, other0 + vb, other0 + vb + length_b * direction};
      } else {
        const Vec3 c = s.in_box(1.0);
        q.start = {other0, a0, a0 + direction, c};
        q.end = {other0 + vb, a0 + va, a0 + va + direction, c + s.in_box(1.0)};
      }
      return q;
    }
  }
  return q;
}

}  // namespace

std::vector<Query> generate_queries(QueryFamily family, QueryKind kind, std::size_t count, std::uint64_t seed,
                                    Scalar scale) {
  Sampler sampler(seed);
  std::vector<Query> out;
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    Query q = one_query(family, kind, sampler);
    for (int k = 0; k < 4; ++k) q.start[k] *= scale, q.end[k] *= scale;
    out.push_back(q);
  }
  return out;
}

ClothLikeSet cloth_like_set(int grid_size, std::uint64_t seed) {
  Sampler s(seed);
  ClothLikeSet set;
  const Scalar spacing = 1.0 / grid_size;
  const int n = grid_size + 1;
  const auto index = [n](int layer, int i, int j) { return layer * n * n + i * n + j; };
  // Two sheets: the second folded back a little above the first, both moving a little.
  for (int layer = 0; layer < 2; ++layer) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const Vec3 jitter = s.in_box(0.15 * spacing);
        const Vec3 p(i * spacing, j * spacing, layer * 0.6 * spacing);
        set.start.push_back(p + jitter);
        const Vec3 drift(0, 0, layer == 0 ? 0.0 : -0.3 * spacing);
        set.end.push_back(p + jitter + drift + s.in_box(0.1 * spacing));
      }
    }
  }
  struct Triangle {
    std::array<int, 3> v;
    int layer, i, j;
  };
  std::vector<Triangle> triangles;
  std::vector<std::array<int, 4>> edges;  // v0, v1, cell i, cell j (+ layer in the vertices)
  for (int layer = 0; layer < 2; ++layer) {
    for (int i = 0; i < grid_size; ++i) {
      for (int j = 0; j < grid_size; ++j) {
        const int a = index(layer, i, j), b = index(layer, i + 1, j), c = index(layer, i + 1, j + 1),
                  d = index(layer, i, j + 1);
        triangles.push_back({{a, b, c}, layer, i, j});
        triangles.push_back({{a, c, d}, layer, i, j});
        edges.push_back({a, b, i, j});
        edges.push_back({a, d, i, j});
        edges.push_back({a, c, i, j});
      }
    }
  }
  const auto near = [](int i0, int j0, int i1, int j1) { return std::abs(i0 - i1) <= 2 && std::abs(j0 - j1) <= 2; };
  for (const Triangle& t : triangles) {
    for (int layer = 0; layer < 2; ++layer) {
      for (int i = std::max(0, t.i - 2); i <= std::min(n - 1, t.i + 2); ++i) {
        for (int j = std::max(0, t.j - 2); j <= std::min(n - 1, t.j + 2); ++j) {
          const int v = index(layer, i, j);
          if (v == t.v[0] || v == t.v[1] || v == t.v[2]) continue;
          set.vertex_face.push_back({v, t.v[0], t.v[1], t.v[2]});
        }
      }
    }
  }
  for (std::size_t e = 0; e < edges.size(); ++e) {
    for (std::size_t f = e + 1; f < edges.size(); ++f) {
      const auto& a = edges[e];
      const auto& b = edges[f];
      if (!near(a[2], a[3], b[2], b[3])) continue;
      if (a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1]) continue;
      set.edge_edge.push_back({a[0], a[1], b[0], b[1]});
    }
  }
  return set;
}

std::vector<Query> gather_queries(const ClothLikeSet& set, QueryKind kind) {
  const auto& pairs = kind == QueryKind::VertexFace ? set.vertex_face : set.edge_edge;
  std::vector<Query> out;
  out.reserve(pairs.size());
  for (const auto& pair : pairs) {
    Query q;
    for (int i = 0; i < 4; ++i) q.start[i] = set.start[pair[i]], q.end[i] = set.end[pair[i]];
    out.push_back(q);
  }
  return out;
}

}  // namespace drape::ccd
