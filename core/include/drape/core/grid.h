#pragma once
/// \file
/// The built-in rectangular cloth: a grid of quads split into triangles.
///
/// The built-in rectangular cloth: a grid of quads split into triangles, in its local plane
/// z = 0, centred on the origin, x along the first size and resolution, y along the second.

#include <optional>
#include <string>

#include "drape/core/mesh.h"

namespace drape {

/// How each quad is split: all along one diagonal, or alternating like a checkerboard.
enum class GridDiagonals { Alternate, Forward, Backward };

struct GridSpec {
  Vec2 size = Vec2(1, 1);             ///< extent along local x and y (scene units)
  std::array<int, 2> resolution{20, 20};  ///< quads along x and y
  GridDiagonals diagonals = GridDiagonals::Alternate;
};

struct GridMesh {
  TriangleMesh mesh;
  GridSpec spec;
  /// Vertex index at grid position (i along x, j along y).
  int index(int i, int j) const { return j * (spec.resolution[0] + 1) + i; }
};

GridMesh make_grid(const GridSpec& spec);

/// Corner names for handles: "bottom-left" (-x, -y), "bottom-right" (+x, -y), "top-left"
/// (-x, +y), "top-right" (+x, +y), in the grid's local frame. nullopt for another name.
std::optional<int> grid_corner(const GridMesh& grid, const std::string& name);

/// The mass-spring layout of a grid (Provot 1995): stretch springs on the axis-aligned edges,
/// shear springs on both diagonals of every quad, bend springs between vertices two apart
/// along x and along y.
struct GridSprings {
  std::vector<Edge> stretch, shear, bend;
};
GridSprings grid_springs(const GridMesh& grid);

}  // namespace drape
