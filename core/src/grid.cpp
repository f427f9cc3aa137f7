#include "drape/core/grid.h"

namespace drape {

GridMesh make_grid(const GridSpec& spec) {
  GridMesh grid;
  grid.spec = spec;
  const int nx = spec.resolution[0], ny = spec.resolution[1];
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      grid.mesh.vertices.emplace_back(spec.size.x() * (Scalar(i) / nx - 0.5), spec.size.y() * (Scalar(j) / ny - 0.5), 0.0);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int a = grid.index(i, j), b = grid.index(i + 1, j), c = grid.index(i + 1, j + 1), d = grid.index(i, j + 1);
      const bool forward = spec.diagonals == GridDiagonals::Forward ||
                           (spec.diagonals == GridDiagonals::Alternate && (i + j) % 2 == 0);
      if (forward) {  // diagonal a-c
        grid.mesh.triangles.push_back({a, b, c});
        grid.mesh.triangles.push_back({a, c, d});
      } else {  // diagonal b-d
        grid.mesh.triangles.push_back({a, b, d});
        grid.mesh.triangles.push_back({b, c, d});
      }
    }
  }
  return grid;
}

std::optional<int> grid_corner(const GridMesh& grid, const std::string& name) {
  const int nx = grid.spec.resolution[0], ny = grid.spec.resolution[1];
  if (name == "bottom-left") return grid.index(0, 0);
  if (name == "bottom-right") return grid.index(nx, 0);
  if (name == "top-left") return grid.index(0, ny);
  if (name == "top-right") return grid.index(nx, ny);
  return std::nullopt;
}

GridSprings grid_springs(const GridMesh& grid) {
  GridSprings springs;
  const int nx = grid.spec.resolution[0], ny = grid.spec.resolution[1];
  const auto add = [](std::vector<Edge>& list, int a, int b) { list.push_back(a < b ? Edge{a, b} : Edge{b, a}); };
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      if (i < nx) add(springs.stretch, grid.index(i, j), grid.index(i + 1, j));
      if (j < ny) add(springs.stretch, grid.index(i, j), grid.index(i, j + 1));
      if (i < nx && j < ny) {
        add(springs.shear, grid.index(i, j), grid.index(i + 1, j + 1));
        add(springs.shear, grid.index(i + 1, j), grid.index(i, j + 1));
      }
      if (i + 2 <= nx) add(springs.bend, grid.index(i, j), grid.index(i + 2, j));
      if (j + 2 <= ny) add(springs.bend, grid.index(i, j), grid.index(i, j + 2));
    }
  }
  return springs;
}

}  // namespace drape
