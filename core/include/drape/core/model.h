#pragma once
/// \file
/// The model: what a scene fixes for a whole run, built once from it.
///
/// The model: everything about a scene that does not change during a run, built once from the
/// scene (meshes loaded and validated, springs, masses, handles, obstacles). The state that
/// changes lives in State; a step is step(const Model&, State&, ...).

#include <array>
#include <memory>
#include <vector>

#include "drape/core/forces.h"
#include "drape/core/mesh.h"
#include "drape/core/scene.h"

namespace drape {

enum class SpringKind : std::uint8_t { Stretch, Shear, Bend };

struct Spring {
  int i = 0, j = 0;       ///< global vertex indices
  Scalar rest_length = 0;
  Scalar stiffness = 0;   ///< N/m
  Scalar damping = 0;     ///< N s/m
  SpringKind kind = SpringKind::Stretch;
  Scalar limit = 0;       ///< largest length over rest length that strain limiting allows (0: none)
  Scalar compression = 1; ///< its constant in compression over its constant in tension (Material::compression)
};

/// One stencil of a cloth's bending, energy 1/2 |u|^2 with u = sum k_i x_i. On a mesh, a hinge of
/// the quadratic bending model (Bergou, Wardetzky, Harmon, Zorin and Grinspun, "A quadratic
/// bending model for inextensible surfaces", SGP 2006): an interior edge (vertices v[0], v[1])
/// and the corners opposite it (v[2], v[3]), the weights k from the rest triangles' cotangents
/// times sqrt(B / (A1 + A2)) (B the bending rigidity, A1 and A2 their areas), calibrated to the
/// triangles' shapes so that a cloth bent into a cylinder of curvature c stores B c^2 / 2 a
/// square metre (model.cpp, calibrate_hinges). On a grid, or a mesh laid out on a grid's
/// lattice, a second difference along a row or a column or a cell's twist (lattice_bending.cpp,
/// add_lattice_bending); a three-point stencil repeats a
/// corner with weight 0. u is zero for every rigid motion and every affine image of the rest
/// shape (uniform stretch, compression or shear in its plane): the model resists bending, not
/// in-plane compression. The force on x_i is -k_i (u + damping du/dt); both are linear in the
/// positions, so the stiffness matrix is constant.
struct Hinge {
  std::array<int, 4> v{};    ///< global vertex indices
  std::array<Scalar, 4> k{};  ///< sqrt(N m) / m
  Scalar damping = 0;         ///< s: the material's damping time
};

/// A hinge's u = sum k_i x_i for the vertices' positions (or, of their velocities, du/dt).
inline Vec3 hinge_vector(const Hinge& hinge, const std::vector<Vec3>& x) {
  Vec3 u = Vec3::Zero();
  for (std::size_t i = 0; i < 4; ++i) u += hinge.k[i] * x[std::size_t(hinge.v[i])];
  return u;
}

/// A hinge's u + damping du/dt at positions x and velocities v: its force on corner i is -k_i
/// times it (hinge_force).
inline Vec3 hinge_pull(const Hinge& hinge, const std::vector<Vec3>& x, const std::vector<Vec3>& v) {
  return hinge_vector(hinge, x) + hinge.damping * hinge_vector(hinge, v);
}

/// A hinge's force on its corner i at positions x and velocities v: -k_i (u + damping du/dt).
/// Its Jacobians are constant: dF_i/dx_j = -k_i k_j I and dF_i/dv_j = -damping k_i k_j I.
inline Vec3 hinge_force(const Hinge& hinge, std::size_t i, const std::vector<Vec3>& x, const std::vector<Vec3>& v) {
  return -hinge.k[i] * hinge_pull(hinge, x, v);
}

/// One triangle of a mesh cloth's membrane (Material::membrane_triangles): its corners (global
/// vertex indices) and its constant strain element (evaluate_membrane).
struct Membrane {
  std::array<int, 3> v{};
  MembraneMaterial material;
};

/// A membrane triangle's corners at positions x.
inline std::array<Vec3, 3> corners(const Membrane& membrane, const std::vector<Vec3>& x) {
  return {x[std::size_t(membrane.v[0])], x[std::size_t(membrane.v[1])], x[std::size_t(membrane.v[2])]};
}

/// The vertices and triangles of one cloth within the global arrays.
struct ClothRange {
  int first_vertex = 0, vertex_count = 0;
  int first_triangle = 0, triangle_count = 0;
  /// A mesh cloth read from an OBJ file: each of the file's vertices, its index within the
  /// cloth or -1 (TriangleMesh::from_file); empty otherwise (a handle's nodes are then the
  /// cloth's own indices).
  std::vector<int> from_file;
  /// An OBJ cloth whose file numbering could not be recovered (number_as_in_file): a handle's
  /// nodes on it are refused.
  bool numbering_lost = false;
  /// Its bending stencils are a grid's (a grid, or a mesh on a grid's lattice), not hinges.
  bool lattice_bending = false;
};

/// A pinned vertex: it follows its handle's motion from its initial position.
struct Pin {
  int vertex = 0;
  int handle = 0;  ///< index into Scene::handles
};

struct Obstacle {
  ObstacleSpec spec;
  TriangleMesh mesh;  ///< mesh obstacles: in world coordinates at t = 0 (transform applied)
};

struct Model {
  Scene scene;
  std::vector<Vec3> initial_positions;  ///< all cloths, concatenated
  std::vector<Vec3> initial_velocities;
  std::vector<Scalar> masses;           ///< lumped: density * area / 3 from each triangle
  std::vector<Scalar> air_damping;      ///< per vertex, 1/s (its cloth's material)
  std::vector<Triangle> triangles;      ///< global vertex indices
  std::vector<ClothRange> cloths;
  std::vector<Spring> springs;          ///< only kinds with nonzero stiffness
  std::vector<Hinge> hinges;            ///< cloths with a bending rigidity only
  std::vector<Membrane> membranes;      ///< mesh cloths with "membrane": "triangles" only
  std::vector<Pin> pins;
  std::vector<int> pin_of_vertex;       ///< index into pins, or -1 for a free vertex
  std::vector<Obstacle> obstacles;
  Box bounds;                           ///< leaving it stops the run (exploded)

  std::size_t vertex_count() const { return initial_positions.size(); }
  /// The cloth mesh with the given positions (all cloths).
  TriangleMesh cloth_mesh(const std::vector<Vec3>& positions) const { return {positions, triangles, {}}; }
};

/// Builds and validates the model. Throws SceneError naming the scene file and the JSON path
/// of what is wrong (a missing or unreadable mesh, a degenerate or non-manifold mesh, a handle
/// naming a vertex or corner the cloth does not have, an empty handle box).
Model build_model(const Scene& scene);

/// The box around everything at the start: the cloths' initial positions, spheres and mesh
/// obstacles (planes have no extent).
Box initial_extent(const Model& model);

}  // namespace drape
