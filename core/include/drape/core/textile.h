#pragma once
/// \file
/// The textile laboratory's measurements on a run (the Cusick drape test, the cantilever test).
///
/// Measurements of the textile laboratory on a simulated cloth: the Cusick drape test's drape
/// coefficient and node count (BS 5058, ISO 9073-9), and the cantilever bending test's bending
/// length (Peirce 1930; ASTM D1388) against the heavy elastica.

#include <vector>

#include "drape/core/mesh.h"

namespace drape {

/// The Cusick test's set-up: a fabric disc of radius fabric_radius centred above a support
/// disc of radius support_radius (BS 5058: 15 cm and 9 cm), seen along `down`.
struct CusickSetup {
  Vec3 centre = Vec3::Zero();        ///< the discs' common axis passes through it
  Vec3 down = -Vec3::UnitZ();        ///< the direction the shadow is cast in (gravity's)
  Scalar fabric_radius = 0.15;       ///< m
  Scalar support_radius = 0.09;      ///< m
};

/// The draped fabric's shadow and what the laboratory reads from it.
struct CusickResult {
  Scalar shadow_area = 0;            ///< m^2: the area of the cloth's projection along down
  Scalar drape_coefficient = 0;      ///< (shadow - support disc) / (fabric disc - support disc): 1 flat, 0 hanging straight
  int nodes = 0;                     ///< folds: peaks of the shadow's outline around the axis
  /// m, a node each, in order around the axis: how far its smoothed outline rises above the
  /// troughs beside it (the lesser side). A count that hangs on a node near NODE_PROMINENCE
  /// times the fabric radius is one a slightly different drape may change.
  std::vector<Scalar> node_depths;
  std::vector<Scalar> outline;       ///< m: the shadow's outermost radius in each of OUTLINE_BINS directions
};

/// Directions the outline is read in (half a degree each).
inline constexpr int OUTLINE_BINS = 720;

/// The shadow is rasterised on a square grid of cells this fraction of the fabric radius wide
/// (0.15 mm for the standard disc: the area to about 0.1 %).
inline constexpr Scalar SHADOW_CELL = 1e-3;

/// A peak of the outline counts as a node when it rises above the troughs on both sides by at
/// least this fraction of the fabric radius (4.5 mm for the standard disc) ...
inline constexpr Scalar NODE_PROMINENCE = 0.03;

/// ... after the outline is smoothed over this many directions on each side (5 degrees).
inline constexpr int OUTLINE_SMOOTHING = 10;

/// Measures the cloth (positions, triangles) against the set-up. Throws std::invalid_argument
/// when the set-up is degenerate (radii not 0 < support < fabric, a zero direction).
CusickResult measure_cusick(const std::vector<Vec3>& positions, const std::vector<Triangle>& triangles, const CusickSetup& setup);

/// The tip's drop (m) of a heavy elastica: Euler's inextensible strip of length `length` (m),
/// clamped level at one end, free at the other, bending under its own weight, with
/// load_over_rigidity = w g / B (1/m^3; weight per unit area over bending rigidity per unit
/// width, 1 / c^3 for the bending length c). Solved numerically on ELASTICA_INTERVALS
/// intervals (textile.cpp says how). Throws std::invalid_argument unless both are finite and
/// positive (a load of 0 drops nothing: 0 is accepted).
Scalar heavy_elastica_drop(Scalar length, Scalar load_over_rigidity);

/// Central-difference intervals of the elastica's solution: its drop to about 1e-7 of the length.
inline constexpr int ELASTICA_INTERVALS = 4000;

/// The bending length c (m) of a heavy elastica of this length whose tip drops by `drop`: the
/// inverse of heavy_elastica_drop, by bisection on log c to a relative BENDING_LENGTH_TOLERANCE.
/// Throws std::invalid_argument unless MIN_DROP_OVER_LENGTH times the length < drop < the drop
/// of a strip of bending length length / MAX_OVERHANG_OVER_BENDING_LENGTH (all but hanging
/// straight down), or when the elastica's Newton iteration does not converge.
Scalar elastica_bending_length(Scalar length, Scalar drop);

inline constexpr Scalar BENDING_LENGTH_TOLERANCE = 1e-6;
/// Drops under this fraction of the length are too small to tell a bending length from.
inline constexpr Scalar MIN_DROP_OVER_LENGTH = 1e-6;
/// Overhangs longer than this many bending lengths hang so nearly straight down (drop 0.9934 of
/// the overhang at 20) that the drop no longer tells the bending length; the solver's
/// continuation also fails beyond about 25.
inline constexpr Scalar MAX_OVERHANG_OVER_BENDING_LENGTH = 20;

/// What the cantilever test reads from a strip clamped at one end (its held vertices) and free
/// at the other, at rest under gravity.
struct CantileverResult {
  Scalar overhang = 0;        ///< m, at the start: from the clamp's edge (the held vertex farthest along the strip) to the tip
  Scalar clamp_offset = 0;    ///< m: half the first free quad, by which the clamped length exceeds the overhang (below)
  Scalar drop = 0;            ///< m: the tip's (the farthest free vertices') mean drop along gravity since the start
  int tip_vertices = 0;
  /// The strip's length as a heavy elastica clamped level: overhang + clamp_offset. A hinge on
  /// the clamp's edge bends over its whole dual cell, half of which lies behind the edge, so a
  /// discrete strip bends from half a quad behind its last held vertex (docs/materials.md).
  Scalar clamped_length() const { return overhang + clamp_offset; }
};

/// The tip: free vertices whose start lies within this fraction of the overhang of the farthest.
inline constexpr Scalar TIP_BAND = 1e-6;

/// Measures a cantilever: initial and current positions, which vertices are held (the clamp),
/// and gravity's direction. The strip runs from the held vertices' centroid towards the free
/// ones' across gravity. Throws std::invalid_argument when there is no clamp, no free vertex,
/// or no overhang across gravity.
CantileverResult measure_cantilever(const std::vector<Vec3>& initial, const std::vector<Vec3>& positions,
                                    const std::vector<bool>& held, const Vec3& down);

}  // namespace drape
