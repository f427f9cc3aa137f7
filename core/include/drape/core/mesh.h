#pragma once
/// \file
/// Triangle meshes, the cloth's and the obstacles', with their topology queries.
///
/// Triangle meshes: the cloth's and the obstacles'. Plain data plus the topology queries the
/// cloth model and the collision pipeline need.

#include <array>
#include <string>
#include <vector>

#include "drape/ccd/types.h"

namespace drape {

using Triangle = std::array<int, 3>;
using Edge = std::array<int, 2>;  ///< vertex indices, smaller first

struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  /// Each vertex of the file it was read from: its vertex here, or -1 when no triangle uses it
  /// (number_as_in_file); empty when the numbering is the mesh's own.
  std::vector<int> from_file;
};

/// Every edge once, smaller index first, in order of first appearance.
std::vector<Edge> mesh_edges(const TriangleMesh& mesh);

/// For each interior edge (shared by exactly two triangles), the two vertices opposite it:
/// the ends of a bending spring.
std::vector<Edge> bending_pairs(const TriangleMesh& mesh);

/// Each interior edge (shared by exactly two triangles with distinct third corners) as the
/// edge's two vertices and then the two opposite corners, in the order of first appearance.
std::vector<std::array<int, 4>> hinges(const TriangleMesh& mesh);

/// What is wrong with a mesh as a simulation input, or "" when nothing is: no triangles, an
/// index out of range, a triangle repeating a vertex, a zero-area triangle (relative to the
/// mesh size), an edge shared by more than two triangles (non-manifold), a non-finite coordinate.
std::string mesh_problem(const TriangleMesh& mesh);

/// Sum of the triangle areas.
Scalar surface_area(const TriangleMesh& mesh);

}  // namespace drape
