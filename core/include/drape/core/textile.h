#pragma once
/// \file
/// The textile laboratory's measurements on a run (the Cusick drape test).
///
/// Measurements of the textile laboratory on a simulated cloth: the Cusick drape test's drape
/// coefficient and node count (BS 5058, ISO 9073-9).

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

}  // namespace drape
