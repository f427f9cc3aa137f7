#pragma once
/// \file
/// Reproducible synthetic CCD queries for tests and benchmarks.
///
/// Reproducible synthetic CCD queries: random families for the agreement and degenerate-case
/// tests, and a cloth-like set for the benchmarks. The same seed gives the same queries.

#include <cstdint>
#include <vector>

#include "drape/ccd/query.h"

namespace drape::ccd {

enum class QueryFamily : std::uint8_t {
  Random,          ///< points and motions uniform in a box: mostly no contact
  Contact,         ///< built to touch at a random time (up to rounding of the construction)
  CoplanarMotion,  ///< all four points stay in the plane z = 0 (the cubic vanishes)
  NearCoplanar,    ///< coplanar motion perturbed by a few ulps
  ParallelEdges,   ///< the two features stay parallel (edge-edge) or edge-aligned (vertex-face)
  TouchAtStart,    ///< touching at t = 0
  TouchAtEnd,      ///< touching at t = 1
  TinyMotion,      ///< motions of about 1e-10 of the feature size
  FarFromOrigin,   ///< the Contact family translated by 1e6
};

inline constexpr QueryFamily ALL_FAMILIES[] = {
    QueryFamily::Random,      QueryFamily::Contact,    QueryFamily::CoplanarMotion,
    QueryFamily::NearCoplanar, QueryFamily::ParallelEdges, QueryFamily::TouchAtStart,
    QueryFamily::TouchAtEnd,  QueryFamily::TinyMotion, QueryFamily::FarFromOrigin};

const char* family_name(QueryFamily family);

/// count queries of one family and kind; scale multiplies every coordinate (1e-8 .. 1e8).
std::vector<Query> generate_queries(QueryFamily family, QueryKind kind, std::size_t count, std::uint64_t seed,
                                    Scalar scale = 1.0);

/// A cloth-like set: a jittered grid of triangles and a second sheet folded just above it,
/// each vertex moving a little (a tenth of the spacing); every vertex-face and edge-edge pair of
/// features within two grid cells and sharing no vertex. Mostly no contact, as in a cloth step.
struct ClothLikeSet {
  std::vector<Vec3> start;
  std::vector<Vec3> end;
  std::vector<std::array<std::int32_t, 4>> vertex_face;  ///< vertex, face corners
  std::vector<std::array<std::int32_t, 4>> edge_edge;    ///< edge a, edge b
};
ClothLikeSet cloth_like_set(int grid_size, std::uint64_t seed);

/// The queries of a cloth-like set, gathered.
std::vector<Query> gather_queries(const ClothLikeSet& set, QueryKind kind);

}  // namespace drape::ccd
