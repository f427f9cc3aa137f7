#pragma once
/// \file
/// The scene a JSON file describes, validated, with every default in the structs.
///
/// The scene: what a JSON scene file describes, validated, with every default in the structs.
/// Immutable once loaded; what changes during a run lives in the simulation state.
///
/// The vocabulary follows ARCSim's scene files (frame_time, frame_steps or timestep, end_time
/// or frames, gravity, cloths, obstacles, handles, wind, friction) plus drape's own sections
/// (material, solver, collisions, output, render). docs/scenes.md describes every key.

#include <filesystem>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "drape/ccd/query.h"
#include "drape/core/grid.h"

namespace drape {

/// A scene file that is malformed. what() names the file, the JSON path and what was expected
/// (for a syntax error, the line and column).
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bounds on a scene's numbers beyond which a run means nothing (or its arithmetic breaks
/// down); validation rejects a value outside them, naming the key. docs/scenes.md lists them.
inline constexpr Scalar MAX_COORDINATE = 1e7;     ///< m: positions (translate, centres, points, boxes, vertices)
inline constexpr Scalar MAX_SIZE = 1e4;           ///< m: grid sizes, sphere radii
inline constexpr Scalar MIN_LENGTH = 1e-6;        ///< m: sphere radii
inline constexpr Scalar MIN_SCALE = 1e-6;         ///< transform scale
inline constexpr Scalar MAX_SCALE = 1e6;          ///< transform scale
inline constexpr Scalar MAX_SPEED = 1e5;          ///< m/s: initial, handle, obstacle and wind velocities
inline constexpr Scalar MAX_ANGULAR_SPEED = 1e4;  ///< rad/s: motion angular velocities
inline constexpr Scalar MAX_ACCELERATION = 1e4;   ///< m/s^2: gravity
inline constexpr Scalar MAX_THICKNESS = 1;        ///< m: collisions.thickness (see also the cloth-size rule in build_model)
inline constexpr int MAX_PROJECTIVE_ITERATIONS = 1000;  ///< solver.iterations
inline constexpr Scalar MIN_STRAIN_LIMIT = 1.001, MAX_STRAIN_LIMIT = 10;  ///< material.strain_limit
inline constexpr Scalar MAX_SHEAR_LOCKING_ANGLE = 89;  ///< material.shear_locking_angle, degrees
inline constexpr Scalar MAX_CHEBYSHEV_RHO = 0.9999;     ///< solver.chebyshev
inline constexpr int MAX_PROJECTIVE_HISTORY = 100;        ///< solver.history
inline constexpr int MAX_FACTOR_REUSE = 1000;             ///< solver.factor_reuse
inline constexpr int MAX_RELEASE_SOLVES = 100;            ///< solver.release_solves
inline constexpr Scalar MAX_THICKNESS_OF_CLOTH = 0.25;  ///< collisions.thickness at most this times each cloth's diagonal
inline constexpr Scalar MAX_AREAL_DENSITY = 1e6;    ///< kg/m^2: material.density (1e9 g/m^2 as mass_per_area)
inline constexpr Scalar MAX_STIFFNESS = 1e9;        ///< N/m (tensile, shear) or N (stretch, shear, bend springs)
inline constexpr Scalar MAX_BENDING_RIGIDITY = 1e3; ///< N m: material.bending_rigidity
inline constexpr Scalar MAX_DAMPING = 1e6;          ///< s (material.damping) and 1/s (air_damping)
inline constexpr Scalar MAX_FLUID_DENSITY = 1e4;    ///< kg/m^3: wind.density
inline constexpr Scalar MAX_COEFFICIENT = 100;      ///< friction, wind.drag
inline constexpr Scalar MIN_FRAME_TIME = 1e-6;    ///< s
inline constexpr Scalar MAX_FRAME_TIME = 60;      ///< s

/// x' = R (scale x) + translate, R a rotation of rotate_degrees about rotate_axis (ARCSim's
/// "rotate": [degrees, x, y, z]).
struct Transform {
  Vec3 translate = Vec3::Zero();
  Scalar rotate_degrees = 0;
  Vec3 rotate_axis = Vec3::UnitZ();
  Scalar scale = 1;
  Vec3 apply(const Vec3& x) const;
};

/// A rigid scripted motion, active between start and end (seconds): translation at a constant
/// velocity and rotation at a constant angular velocity (axis times radians per second) about
/// a centre that travels with the translation.
struct Motion {
  Vec3 velocity = Vec3::Zero();
  Vec3 angular_velocity = Vec3::Zero();
  Vec3 center = Vec3::Zero();
  Scalar start = 0;
  Scalar end = std::numeric_limits<Scalar>::infinity();
  /// Where a point at x at time 0 is at time t.
  Vec3 position(const Vec3& x, Scalar t) const;
  /// The velocity at time t of the point that was at x at time 0.
  Vec3 velocity_at(const Vec3& x, Scalar t) const;
  bool moves() const { return !velocity.isZero() || !angular_velocity.isZero(); }
};

/// Per-cloth material. Spring constants follow from these and each spring's rest length L:
/// k = stiffness / L, so a spring's force is stiffness times its strain (a finer grid puts more
/// springs across the same width: its sheet is stiffer; the fabric keys below are not). A
/// stiffness of zero creates no springs of that kind.
struct Material {
  Scalar density = 0.15;   ///< kg per square metre of cloth
  Scalar stretch = 2000;   ///< N: structural springs (grid axes; every edge of an imported mesh)
  Scalar shear = 200;      ///< N: both diagonals of each grid quad (grids only)
  Scalar bend = 2;         ///< N: springs across one vertex (grids) or across each interior edge
  /// N m: the fabric's bending rigidity (moment per unit width over curvature, as Kawabata's
  /// and the cantilever test's); above zero it selects the hinge bending model (Model::hinges)
  /// instead of the bending springs.
  Scalar bending_rigidity = 0;
  Scalar damping = 0.002;  ///< s: each spring's damping is this times its stiffness
  /// 1/s: still air's drag on each particle, -air_damping m (v - wind velocity); it is what
  /// brings a swinging cloth to rest (spring damping does not damp rigid swinging).
  Scalar air_damping = 0.1;
  /// N/m: the fabric's tensile stiffness (force per unit width over strain in a strip test,
  /// free to narrow) and shear stiffness (force per unit width over shear angle); above zero
  /// they give the springs' constants from the cloth's geometry in place of `stretch` and
  /// `shear` (add_fabric_grid_springs and add_fabric_mesh_springs in model.cpp), the same
  /// sheet at any resolution.
  Scalar tensile_stiffness = 0;
  Scalar shear_stiffness = 0;
  /// The largest stretch the fabric allows (a structural spring's length over its rest
  /// length, above 1), kept by strain limiting after each step's solve; 0: none.
  Scalar strain_limit = 0;
  /// Degrees: the largest shear angle a grid's fabric allows (its locking angle, where the
  /// yarns jam), kept by limiting its shear springs (the cells' diagonals) to the length an
  /// a x b cell's diagonal reaches at that angle with both sides at strain_limit:
  /// strain_limit sqrt(1 + 2 a b sin(angle) / (a^2 + b^2)); 0: the diagonals are not limited.
  Scalar shear_locking_angle = 0;
  /// The springs' constant in compression over their constant in tension, from 0 to 1: woven
  /// and knitted fabrics barely resist in-plane compression (they buckle at the yarns' scale),
  /// where a linear spring (1) resists it as it resists stretching. The cholmod and cg solvers.
  Scalar compression = 1;
  /// How a mesh cloth's fabric (tensile_stiffness and shear_stiffness) holds its plane: false
  /// ("membrane": "springs"), edge springs fitted triangle by triangle, which hold the fabric's
  /// shear on right triangles along the warp and weft and shear up to 57 times too stiffly on
  /// other shapes; true ("triangles"), each triangle a constant strain element
  /// (MembraneMaterial), exact on every shape. The cholmod and cg solvers.
  bool membrane_triangles = false;
};

struct ClothSpec {
  std::optional<GridSpec> grid;       ///< the built-in grid generator, or
  std::filesystem::path mesh_file;    ///< a mesh read by assimp (resolved against the scene's folder)
  Transform transform;
  Material material;
  Vec3 velocity = Vec3::Zero();  ///< initial velocity of every vertex (m/s)
  std::string render_json;       ///< the cloth's render section (its colours), kept verbatim for the renderer
};

struct Box {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();
  bool contains(const Vec3& x) const { return (x.array() >= min.array()).all() && (x.array() <= max.array()).all(); }
};

/// A ball: the vertices whose initial positions lie within `radius` of `center`.
struct Ball {
  Vec3 center = Vec3::Zero();
  Scalar radius = 0;
  bool contains(const Vec3& x) const { return (x - center).norm() <= radius; }
};

/// Pinned vertices of one cloth, chosen by index, by grid corner name, or by a box or a ball
/// around their initial positions; they follow motion when given, else stay put.
struct HandleSpec {
  int cloth = 0;
  std::vector<int> nodes;
  std::vector<std::string> corners;
  std::optional<Box> box;
  std::optional<Ball> ball;  ///< e.g. the Cusick test's clamp: a disc of the cloth around its centre
  Motion motion;
};

struct ObstacleSpec {
  enum class Kind { Sphere, Plane, Mesh };
  Kind kind = Kind::Plane;
  Vec3 center = Vec3::Zero();  ///< sphere
  Scalar radius = 1;           ///< sphere
  Vec3 point = Vec3::Zero();   ///< plane: a point on it
  Vec3 normal = Vec3::UnitZ(); ///< plane: unit normal, the free side
  std::filesystem::path mesh_file;  ///< mesh (resolved against the scene's folder)
  Transform transform;              ///< mesh
  Motion motion;
};

/// Air flowing at velocity: each triangle feels a drag along its normal,
/// 0.5 density drag area |w_n| w_n, with w_n the normal component of the relative velocity.
struct WindSpec {
  Vec3 velocity = Vec3::Zero();  ///< m/s
  Scalar density = 1.2;          ///< kg/m^3 (air)
  Scalar drag = 1.0;             ///< dimensionless drag coefficient
};

/// cholmod: linearised backward Euler, a sparse Cholesky factorisation every step (the accurate
/// reference); cg: the same system by conjugate gradient; projective: the local-global solver
/// for mass-spring systems (projective dynamics), one factorisation for the run.
enum class SolverKind { Cholmod, ConjugateGradient, Projective };

/// solver.tolerance's default for a solver type: cg's relative residual, or the projective
/// solver's share of an edge (SolverSpec::tolerance; 0: every one of its iterations until no
/// vertex could move a millionth of an edge).
inline constexpr Scalar CG_TOLERANCE = 1e-8;
inline constexpr Scalar PROJECTIVE_TOLERANCE = 0;

struct SolverSpec {
  SolverKind kind = SolverKind::Cholmod;
  /// cg: relative residual at which it stops; projective: it stops before `iterations` after
  /// an iteration that moved no vertex by more than this times the mean edge length. Its
  /// default depends on the type (CG_TOLERANCE, PROJECTIVE_TOLERANCE).
  Scalar tolerance = CG_TOLERANCE;
  int max_iterations = 2000;  ///< cg: iteration cap
  /// cholmod: conjugate gradient iterations, preconditioned by the last factorisation, that a
  /// solve may take (until its preconditioned residual norm is 1e-10 of the right-hand
  /// side's: the error in the matrix's norm) before its own matrix is factorised; 0 factorises
  /// every solve.
  int factor_reuse = 1;
  /// A step that makes energy (beyond a tolerance) is taken again in 2, 4, ... parts, at most
  /// 2^max_halvings (Integrator::step); 0 takes every step as it comes.
  int max_halvings = 3;
  /// cholmod: how many times a step may be solved again to release contacts held in the solve
  /// whose force pulls, between the cloth's layers or at a moving obstacle (a still
  /// obstacle's pull alone is released at the next step); 0 releases every pull at the next
  /// step.
  int release_solves = 1;
  /// projective: iterations a step, each one back-substitution with the run's factorisation
  /// and one pass over the springs (more when L-BFGS shortens its step).
  int iterations = 10;
  /// projective with history 0: the iteration's spectral radius estimate for Chebyshev
  /// acceleration (Wang 2015), from 0 (none) to below 1; an accelerated iteration that raises
  /// the step's objective is undone and the acceleration restarts.
  Scalar chebyshev = 0.99;
  /// projective: the quasi-Newton memory (L-BFGS with the run's factorisation as its first
  /// inverse Hessian, Liu, Bouaziz and Kavan 2017); 0: plain local-global iterations, with
  /// `chebyshev`.
  int history = 5;
};

/// The default tolerance of a solver type (0 for cholmod, which has none).
inline Scalar default_tolerance(SolverKind kind) {
  return kind == SolverKind::Projective ? PROJECTIVE_TOLERANCE : CG_TOLERANCE;
}

struct CollisionSpec {
  bool self = false;
  bool obstacles = true;
  Scalar thickness = 0.005;  ///< m: the gap kept between cloth and anything it touches
  ccd::Method method = ccd::Method::Vincent;
  int max_impulse_iterations = 8;  ///< CCD-impulse rounds per step before impact zones
  int max_zone_iterations = 16;    ///< impact-zone rounds per step before the fail-safe
  /// Drop the feature pairs of overlapping triangles whose own swept 18-DOPs are apart before
  /// the narrow phase (ccd::vertex_volumes, ccd::feature_pairs). Changes the cost, never the
  /// contacts found.
  bool feature_boxes = true;
  /// Self-collision: leave out the pairs inside patches of cloth proven free of self-contact
  /// over the step by a continuous normal cone and a contour test (ccd::PatchTree). Changes the
  /// cost, and drops pairs inside such patches that never touch (their proximity repulsion, and
  /// near misses the narrow phase would report within its tolerance); never a contact.
  bool self_culling = true;
  /// Self-collision with the linearised solver (`cholmod`): the cloth's contacts with itself at
  /// the step's start held in the implicit solve, as the obstacles' are (their two sides'
  /// approach along the normal stopped within the step), before the response's impulses.
  bool self_in_solve = true;
};

struct OutputSpec {
  std::filesystem::path folder;  ///< default: out/<scene file name without extension>
  std::string mesh_format = "obj";
  bool meshes = true;            ///< write the cloth mesh of every frame
};

/// When a run warns and when it stops for energy and stretch (the "limits" section). Energy is
/// held against its start plus the work of the scene's sources (handles, wind, moving
/// obstacles; gravity is in the potential energy), with a margin that is a fraction of the
/// scene's energy scale (energy_scale in integrator.h: a fall across the scene). Stretch is the
/// largest structural spring's length over its rest length.
struct RunLimits {
  Scalar energy_warn = 0.05;  ///< a frame whose energy exceeds the bound by this much warns
  Scalar energy_stop = 0.5;   ///< and by this much stops the run (status 3)
  Scalar stretch_warn = 1.25; ///< a frame stretched beyond this warns
  Scalar stretch_stop = 2.0;  ///< and beyond this stops the run
};

struct Scene {
  std::filesystem::path file;  ///< the scene file, when read from one
  std::string text;            ///< the JSON as read (a run folder's copy is made from it)
  std::string comment;
  Scalar frame_time = 1.0 / 30;  ///< s
  int frame_steps = 10;          ///< implicit steps per frame
  int frames = 60;
  Vec3 gravity = Vec3(0, 0, -9.81);
  std::vector<ClothSpec> cloths;
  std::vector<HandleSpec> handles;
  std::vector<ObstacleSpec> obstacles;
  std::optional<WindSpec> wind;
  Scalar friction = 0.3;  ///< Coulomb coefficient between cloth and obstacles
  SolverSpec solver;
  CollisionSpec collisions;
  OutputSpec output;
  /// The run stops (exploded) when a cloth vertex leaves this box; default: the initial
  /// bounding box of everything, grown by 100 times its diagonal.
  std::optional<Box> bounds;
  std::string render_json;  ///< the render section, kept verbatim for the renderer
  RunLimits limits;

  Scalar timestep() const { return frame_time / frame_steps; }
};

/// Reads and validates a scene file. Throws SceneError.
Scene load_scene(const std::filesystem::path& path);

/// Parses scene text; file names the source in messages and anchors relative mesh paths.
Scene parse_scene(const std::string& text, const std::filesystem::path& file);

}  // namespace drape
