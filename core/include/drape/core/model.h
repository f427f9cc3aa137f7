#pragma once
/// \file
/// The model: everything about a scene that does not change during a run, built once from the
/// scene (meshes loaded and validated, springs, masses, handles, obstacles). The state that
/// changes lives in State; a step is step(const Model&, State&, ...).

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
};

/// The vertices and triangles of one cloth within the global arrays.
struct ClothRange {
  int first_vertex = 0, vertex_count = 0;
  int first_triangle = 0, triangle_count = 0;
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
  std::vector<Pin> pins;
  std::vector<int> pin_of_vertex;       ///< index into pins, or -1 for a free vertex
  std::vector<Obstacle> obstacles;
  Box bounds;                           ///< leaving it stops the run (exploded)

  std::size_t vertex_count() const { return initial_positions.size(); }
  /// The cloth mesh with the given positions (all cloths).
  TriangleMesh cloth_mesh(const std::vector<Vec3>& positions) const { return {positions, triangles}; }
};

/// Builds and validates the model. Throws SceneError naming the scene file and the JSON path
/// of what is wrong (a missing or unreadable mesh, a degenerate or non-manifold mesh, a handle
/// naming a vertex or corner the cloth does not have, an empty handle box).
Model build_model(const Scene& scene);

/// The box around everything at the start: the cloths' initial positions, spheres and mesh
/// obstacles (planes have no extent).
Box initial_extent(const Model& model);

}  // namespace drape
