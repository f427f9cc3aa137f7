#pragma once
/// \file
/// The bending of a cloth laid out on a regular lattice of cells: a grid cloth, or a mesh
/// cloth whose every triangle is half of one of a flat lattice's cells (a grid exported as a
/// mesh, a disc cut from one). Such a cloth bends by the grid's discrete Hessian, alike in
/// every direction, where the hinges of its right triangles would not.

#include <optional>
#include <vector>

#include "drape/core/grid.h"
#include "drape/core/model.h"

namespace drape {

/// Lattice points (i, j), i in [0, columns] along the first axis (cells of side a), j in
/// [0, rows] along the second (side b), each a cloth vertex or none; which of the lattice's
/// unit edges and cells the cloth has; each point's share of the cloth's area.
struct Lattice {
  Scalar a = 0, b = 0;
  int columns = 0, rows = 0;
  std::vector<int> vertex;             ///< per point: global vertex index, or -1
  std::vector<int> eighths;            ///< per point: its share of the area in eighths of a cell
  std::vector<char> along_i, along_j;  ///< per point: the edge to (i + 1, j), to (i, j + 1)
  std::vector<char> whole_cell;        ///< per point: the cell from it to (i + 1, j + 1), both of its triangles
  int point(int i, int j) const { return j * (columns + 1) + i; }
};

/// The grid's lattice (every point, edge and cell) with cells of sides a and b, its vertices
/// from offset on.
Lattice grid_lattice(const GridMesh& grid, int offset, Scalar a, Scalar b);

/// The lattice a mesh cloth lies on, or nullopt: every vertex within LATTICE_TOLERANCE of a
/// point of a flat lattice (axes from the first triangle's right angle, then fitted to every
/// vertex by least squares; positions from the model, global index = mesh index + offset), no
/// two on one point, and every triangle half of one cell, a cell's two triangles sharing its
/// diagonal. A lattice 64 times larger than the mesh's vertex count (a long thin diagonal
/// strip) is not taken: such a mesh keeps its hinges.
std::optional<Lattice> mesh_lattice(const Model& model, const TriangleMesh& mesh, int offset);

/// How far from its lattice point a vertex may lie, relative to the cell's shorter side: OBJ
/// files written with six decimals (Blender's) round coordinates by up to 5e-7 m in each, 1e-4
/// of a 7 mm cell; a vertex moved by a hundredth of a cell is off the lattice.
inline constexpr Scalar LATTICE_TOLERANCE = 1e-3;
/// How far from a right angle the first triangle's corner may be (its cosine) to give the
/// lattice's axes, which the fit to every vertex then refines and checks.
inline constexpr Scalar AXES_TOLERANCE = 1e-2;

/// The lattice's bending for rigidity B (N m) as stencils of the hinges' form (Hinge):
/// every point between two others along a row of present edges gets u = (x[i-1] - 2 x[i] +
/// x[i+1]) sqrt(B A) / a^2, A its share of the area, and likewise along a column; every whole
/// cell gets its twist, u = (x00 - x10 - x01 + x11) sqrt(2 B a b) / (a b). Their energy is
/// B (x_uu^2 + x_vv^2 + 2 x_uv^2) / 2 a square metre: B c^2 / 2 for a bend of curvature c in
/// any direction, nothing for an in-plane affine map, and stiffness against every pattern of
/// vertices up and down.
void add_lattice_bending(Model& model, const Lattice& lattice, Scalar rigidity, Scalar damping_time);

}  // namespace drape
