#pragma once
/// \file
/// Degenerate CCD queries enumerated by family, for tests and benchmarks.
///
/// Degenerate CCD queries, enumerated systematically (docs/ccd.md, "Degenerate families"): a
/// feature that degenerates (a triangle of zero area, an edge of zero length, edges on one
/// line) at the start of the step, at its end, at one moment within it or throughout, with the
/// other feature placed on the degenerate one's interior, on its boundary, on its extension or
/// a few units in the last place beside it at that moment. Every coordinate is a small dyadic
/// number times a power of two, so the construction is exact in double at every scale; the
/// exact reference (exact_reference.h) gives the ground truth.

#include <cstdint>
#include <string>
#include <vector>

#include "drape/ccd/query.h"

namespace drape::ccd {

/// What degenerates.
enum class DegenerateShape : std::uint8_t {
  CollinearTriangle,   ///< vertex-face: three distinct corners on one line
  TwoCornersMeet,      ///< vertex-face: two corners coincide (the triangle is a segment)
  ThreeCornersMeet,    ///< vertex-face: all three corners coincide (the triangle is a point)
  ZeroLengthEdge,      ///< edge-edge: one edge is a point
  TwoZeroLengthEdges,  ///< edge-edge: both edges are points
  CollinearEdges,      ///< edge-edge: both edges on one line
};

/// When it is degenerate.
enum class DegenerateWhen : std::uint8_t {
  AtStart,     ///< at t = 0 only
  AtEnd,       ///< at t = 1 only
  Midstep,     ///< at one time inside the step (the triangle or edge flips through it)
  Throughout,  ///< for the whole step (and the placement below holds for the whole step)
};

/// Where the other feature is at that moment, along the degenerate one.
enum class DegeneratePlacement : std::uint8_t {
  Interior,   ///< on the degenerate feature, inside it (a contact)
  Boundary,   ///< on its end point (a contact)
  Extension,  ///< on its line, outside it
  Beside,     ///< off its interior by 2^-40 of the scale (a near miss, unless the motion meets)
};

struct DegenerateCase {
  QueryKind kind = QueryKind::VertexFace;
  DegenerateShape shape = DegenerateShape::CollinearTriangle;
  DegenerateWhen when = DegenerateWhen::AtStart;
  DegeneratePlacement placement = DegeneratePlacement::Interior;
};

/// Every meaningful combination (placements a shape cannot have, such as the interior of a
/// point, are left out): the table of docs/ccd.md.
std::vector<DegenerateCase> degenerate_cases();

/// "vertex-face collinear-triangle at-start interior".
std::string describe(const DegenerateCase& c);

/// count queries of the case from the seed; every coordinate multiplied by 2^scale_exponent
/// (-27 to 27 covers 1e-8 to 1e8).
std::vector<Query> generate_degenerate_queries(const DegenerateCase& c, std::size_t count, std::uint64_t seed,
                                               int scale_exponent);

}  // namespace drape::ccd
