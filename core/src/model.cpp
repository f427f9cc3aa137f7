#include "drape/core/model.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include "drape/core/mesh_io.h"
#include "lattice_bending.h"

namespace drape {
namespace {

[[noreturn]] void fail(const Scene& scene, const std::string& path, const std::string& what) {
  throw SceneError(scene.file.string() + ": " + path + ": " + what);
}

TriangleMesh read_mesh(const Scene& scene, const std::filesystem::path& file, const std::string& path) {
  TriangleMesh mesh;
  try {
    mesh = load_mesh(file);
  } catch (const MeshFileError& e) {
    fail(scene, path, e.what());
  }
  if (const std::string problem = mesh_problem(mesh); !problem.empty()) fail(scene, path, file.string() + ": " + problem);
  return mesh;
}

// Each edge (local indices, offset to the cloth's first vertex) a spring of the constant its
// rest length gives, k(rest) in N/m, damped by damping_time times k; edges of zero length none.
template <class Constant>
void add_edge_springs(Model& model, const std::vector<Edge>& edges, int offset, Scalar damping_time, SpringKind kind,
                      Constant k_of) {
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const int i = edges[e][0] + offset, j = edges[e][1] + offset;
    const Scalar rest = (model.initial_positions[std::size_t(i)] - model.initial_positions[std::size_t(j)]).norm();
    if (!(rest > 0)) continue;
    const Scalar k = k_of(e, rest);
    model.springs.push_back({i, j, rest, k, damping_time * k, kind});
  }
}

void add_springs(Model& model, const std::vector<Edge>& edges, int offset, Scalar stiffness, Scalar damping_time,
                 SpringKind kind) {
  if (stiffness <= 0) return;  // a scene pays only for what it asks for
  add_edge_springs(model, edges, offset, damping_time, kind, [&](std::size_t, Scalar rest) { return stiffness / rest; });
}

// The sides a (along x) and b of a grid's cells, from its placed vertices (offset: its first).
std::pair<Scalar, Scalar> cell_sides(const Model& model, const GridMesh& grid, int offset) {
  const auto at = [&](int i, int j) { return model.initial_positions[std::size_t(grid.index(i, j) + offset)]; };
  return {(at(1, 0) - at(0, 0)).norm(), (at(0, 1) - at(0, 0)).norm()};
}

// The springs of a fabric's tensile stiffness T and shear stiffness G (N/m) on a grid of a x b
// cells: axis springs kx (along a) and ky, and both diagonals kd, whose network has the
// stiffness C11 = kx a / b + G a^2 / b^2, C22 = ky b / a + G b^2 / a^2, C12 = C66 = 2 kd a b / d^2
// (d^2 = a^2 + b^2; the springs' strain energy over a cell's area). So kd = G d^2 / (2 a b),
// and C11 = C22 = s with s - G^2 / s = T (a strip free to narrow stretches by T per unit width):
// s = (T + sqrt(T^2 + 4 G^2)) / 2. An axis spring on the cloth's border serves one cell, not
// two: half of it. Refused (with why) where the cells are too elongated for G.
void add_fabric_grid_springs(Model& model, const GridMesh& grid, const GridSprings& springs, int offset,
                             const Material& m, const Scene& scene, const std::string& path) {
  const int columns = grid.spec.resolution[0] + 1, ny = grid.spec.resolution[1];
  const auto [a, b] = cell_sides(model, grid, offset);
  const Scalar d2 = a * a + b * b;
  const Scalar T = m.tensile_stiffness, G = m.shear_stiffness;
  const Scalar s = 0.5 * (T + std::hypot(T, 2 * G));
  const Scalar kx = s * b / a - G * a / b, ky = s * a / b - G * b / a, kd = G * d2 / (2 * a * b);
  if (!(kx > 0 && ky > 0 && kd > 0 && std::isfinite(kx) && std::isfinite(ky) && std::isfinite(kd))) {
    std::ostringstream what;
    what << "the grid's quads (" << a << " x " << b << " m) are too elongated for a shear stiffness of " << G
         << " N/m with a tensile stiffness of " << T << " N/m (their springs would need a negative or infinite "
         << "constant); expected quads closer to square and stiffnesses of a fabric";
    fail(scene, path + "/material/shear_stiffness", what.str());
  }
  add_edge_springs(model, springs.stretch, offset, m.damping, SpringKind::Stretch, [&](std::size_t e, Scalar) {
    const int u = springs.stretch[e][0], v = springs.stretch[e][1];
    const bool along_x = v - u == 1;  // else a column's edge, v - u = columns
    const bool border = along_x ? u / columns == 0 || u / columns == ny : u % columns == 0 || u % columns == columns - 1;
    return (border ? 0.5 : 1.0) * (along_x ? kx : ky);
  });
  add_edge_springs(model, springs.shear, offset, m.damping, SpringKind::Shear, [&](std::size_t, Scalar) { return kd; });
}

// The edge springs of a fabric's tensile stiffness T on a triangle mesh with no shear
// stiffness given: each edge gets T times its triangles' area over its length squared (van
// Gelder, "Approximate simulation of elastic membranes by triangulated spring meshes", 1998),
// which makes a mesh of equilateral triangles an isotropic sheet of tensile stiffness T
// (Poisson's ratio 1/3, shear 3 T / 8).
void add_isotropic_mesh_springs(Model& model, const TriangleMesh& mesh, int offset, const Material& m) {
  std::map<Edge, Scalar> area;
  for (const Triangle& t : mesh.triangles) {
    const Vec3& p = model.initial_positions[std::size_t(t[0] + offset)];
    const Scalar a = 0.5 * (model.initial_positions[std::size_t(t[1] + offset)] - p)
                               .cross(model.initial_positions[std::size_t(t[2] + offset)] - p)
                               .norm();
    for (int k = 0; k < 3; ++k) area[Edge{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}] += a;
  }
  const std::vector<Edge> edges = mesh_edges(mesh);
  add_edge_springs(model, edges, offset, m.damping, SpringKind::Stretch,
                   [&](std::size_t e, Scalar rest) { return m.tensile_stiffness * area[edges[e]] / (rest * rest); });
}

// One triangle's share of its three edges' spring constants for the grid's sheet of tensile
// stiffness T and shear stiffness G (add_fabric_grid_springs: C11 = C22 = axial, C12 = C66 = G).
// A spring of constant k and rest length l along the unit direction (c, s) of the fabric's
// warp and weft in the triangle's plane adds w = k l^2 / A to the stiffness of a sheet of the
// triangle's area A: C11 += w c^4, C22 += w s^4, C12 = C66 += w c^2 s^2 (a spring network
// obeys Cauchy's relation C12 = C66, as the grid's does). Where the three equations have a
// solution with every weight positive (edges along the warp, the weft and a diagonal, as in a
// grid exported as right triangles), that is the triangle's share. Elsewhere (an equilateral
// triangle's springs give C22 = 3 C66 whatever their weights when an edge lies along the
// warp) the tension comes first: the least squares of the three equations with the tension's
// relative errors TENSION_FIRST times the shear's, every weight at least MIN_WEIGHT axial (a
// triangle with a spring of no weight is a mechanism: an irregular cloth without the floor
// stretched a spring 2.7 times over within 10 frames), found over the subsets of the edges.
constexpr Scalar TENSION_FIRST = 1e4;
constexpr Scalar MIN_WEIGHT = 0.05;
std::array<Scalar, 3> fit_triangle_springs(const std::array<Eigen::Matrix<Scalar, 2, 1>, 3>& directions, Scalar axial,
                                           Scalar G) {
  Eigen::Matrix<Scalar, 3, 3> M;  // each equation relative to its target, the tension's weighed
  for (int e = 0; e < 3; ++e) {
    const Scalar c2 = directions[std::size_t(e)].x() * directions[std::size_t(e)].x();
    const Scalar s2 = directions[std::size_t(e)].y() * directions[std::size_t(e)].y();
    M.col(e) << TENSION_FIRST * c2 * c2 / axial, TENSION_FIRST * s2 * s2 / axial, c2 * s2 / G;
  }
  const Eigen::Matrix<Scalar, 3, 1> goal(TENSION_FIRST, TENSION_FIRST, 1);
  const Eigen::Matrix<Scalar, 3, 1> exact = M.colPivHouseholderQr().solve(goal);
  if (exact.allFinite() && (exact.array() > 0).all() && (M * exact - goal).norm() < 1e-9 * goal.norm())
    return {exact[0], exact[1], exact[2]};
  const Scalar floor = MIN_WEIGHT * axial;
  const Eigen::Matrix<Scalar, 3, 1> target = goal - M * Eigen::Matrix<Scalar, 3, 1>::Constant(floor);
  Scalar best = std::numeric_limits<Scalar>::infinity();
  std::array<Scalar, 3> weights{floor, floor, floor};
  for (int subset = 7; subset >= 1; --subset) {  // every edge first
    std::array<int, 3> used{};
    int count = 0;
    for (int e = 0; e < 3; ++e)
      if (subset & (1 << e)) used[std::size_t(count++)] = e;
    Eigen::Matrix<Scalar, 3, Eigen::Dynamic> A(3, count);
    for (int k = 0; k < count; ++k) A.col(k) = M.col(used[std::size_t(k)]);
    const Eigen::Matrix<Scalar, Eigen::Dynamic, 1> w = A.colPivHouseholderQr().solve(target);
    if (!w.allFinite() || (w.array() < 0).any()) continue;
    const Scalar residual = (A * w - target).norm();
    if (residual < best) {
      best = residual;
      weights = {floor, floor, floor};
      for (int k = 0; k < count; ++k) weights[std::size_t(used[std::size_t(k)])] += w[k];
    }
  }
  return weights;
}

// The warp and weft laid into a triangle's plane (normal n): the warp's part in the plane and
// the normal across it (the weft's part where the triangle faces the warp).
std::pair<Vec3, Vec3> fabric_axes(const Vec3& n, const Vec3& warp, const Vec3& weft) {
  Vec3 u = warp - warp.dot(n) * n;
  if (u.norm() < 0.5) u = weft - weft.dot(n) * n;
  u.normalize();
  return {u, n.cross(u)};
}

// The edge springs of a fabric's tensile stiffness T and shear stiffness G on a triangle mesh:
// each triangle's share fitted (fit_triangle_springs) with the warp the cloth's local x axis
// (warp, after its transform) laid into the triangle's plane (its y axis where the triangle
// faces x), an edge's constant the sum of its triangles' w A / l^2.
void add_fabric_mesh_springs(Model& model, const TriangleMesh& mesh, int offset, const Material& m, const Vec3& warp,
                            const Vec3& weft) {
  const Scalar T = m.tensile_stiffness, G = m.shear_stiffness;
  const Scalar axial = 0.5 * (T + std::hypot(T, 2 * G));
  std::map<Edge, Scalar> constant;
  for (const Triangle& t : mesh.triangles) {
    const auto x = [&](int k) -> const Vec3& { return model.initial_positions[std::size_t(t[std::size_t(k)] + offset)]; };
    const Vec3 normal = (x(1) - x(0)).cross(x(2) - x(0));
    const Scalar area = 0.5 * normal.norm();
    const auto [u, v] = fabric_axes(normal.normalized(), warp, weft);
    std::array<Eigen::Matrix<Scalar, 2, 1>, 3> directions;
    std::array<Scalar, 3> lengths{};
    for (int k = 0; k < 3; ++k) {
      const Vec3 d = x((k + 1) % 3) - x(k);
      lengths[std::size_t(k)] = d.norm();
      directions[std::size_t(k)] = Eigen::Matrix<Scalar, 2, 1>(d.dot(u), d.dot(v)) / lengths[std::size_t(k)];
    }
    const std::array<Scalar, 3> w = fit_triangle_springs(directions, axial, G);
    for (int k = 0; k < 3; ++k)
      constant[Edge{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}] +=
          w[std::size_t(k)] * area / (lengths[std::size_t(k)] * lengths[std::size_t(k)]);
  }
  const std::vector<Edge> edges = mesh_edges(mesh);
  add_edge_springs(model, edges, offset, m.damping, SpringKind::Stretch, [&](std::size_t e, Scalar) { return constant[edges[e]]; });
}

// The membrane of a fabric's tensile stiffness T and shear stiffness G on a triangle mesh
// (Material::membrane_triangles): each triangle a constant strain element in the warp and weft
// laid into its plane (fabric_axes), with the stiffness of the grid's sheet
// (add_fabric_grid_springs): c11 = c22 = axial, c12 = c66 = G, so that a strip free to narrow
// stretches by T and the two models agree wherever the springs are exact.
void add_membranes(Model& model, const TriangleMesh& mesh, int offset, const Material& m, const Vec3& warp, const Vec3& weft) {
  const Scalar T = m.tensile_stiffness, G = m.shear_stiffness;
  const Scalar axial = 0.5 * (T + std::hypot(T, 2 * G));
  for (const Triangle& t : mesh.triangles) {
    Membrane membrane;
    for (std::size_t k = 0; k < 3; ++k) membrane.v[k] = t[k] + offset;
    const auto x = [&](std::size_t k) -> const Vec3& { return model.initial_positions[std::size_t(membrane.v[k])]; };
    const Vec3 normal = (x(1) - x(0)).cross(x(2) - x(0));
    const auto [u, v] = fabric_axes(normal.normalized(), warp, weft);
    Mat2 edges;
    edges << (x(1) - x(0)).dot(u), (x(2) - x(0)).dot(u), (x(1) - x(0)).dot(v), (x(2) - x(0)).dot(v);
    MembraneMaterial& mm = membrane.material;
    mm.rest_inverse = edges.inverse();
    mm.area = 0.5 * normal.norm();
    mm.c11 = mm.c22 = axial;
    mm.c12 = mm.c66 = G;
    mm.damping = m.damping;
    model.membranes.push_back(membrane);
  }
}

// A hinge weight below this share of the hinge's largest is a right angle's zero (a
// triangle's right angle at an edge's end), whatever the rounding of a rotated cloth's
// cotangents (about 1e-16 of them): set to zero so the solvers leave its blocks out.
constexpr Scalar ZERO_HINGE_WEIGHT = 1e-12;

// A hinge's energy for a bend of unit curvature, averaged over the bend's directions, and what
// a fabric of rigidity B stores over the area the hinge serves, B / 2 times (A1 + A2) / 3: its
// two triangles unfolded into a plane (points p_i), a bend z = (d . p)^2 / 2 in direction d
// gives u = d^T M d with M = sum k_i p_i p_i^T / 2, whose square averages ((a + c) / 2)^2 +
// (((a - c) / 2)^2 + b^2) / 2 over d for M = [a b; b c].
struct BendEnergy {
  Scalar energy = 0;    ///< the hinges' (or hinge's), averaged over the bend's directions
  Scalar expected = 0;  ///< the fabric's over the area they serve
};
BendEnergy hinge_bend_energy(const Hinge& hinge, const std::vector<Vec3>& rest, Scalar rigidity) {
  const auto x = [&](int i) -> const Vec3& { return rest[std::size_t(hinge.v[std::size_t(i)])]; };
  const Vec3 e0 = x(1) - x(0);
  const Scalar length = e0.norm();
  const Vec3 t = e0 / length;
  const auto unfolded = [&](int i, Scalar side) {
    const Vec3 r = x(i) - x(0);
    return Eigen::Matrix<Scalar, 2, 1>(r.dot(t), side * (r - r.dot(t) * t).norm());
  };
  const Eigen::Matrix<Scalar, 2, 1> p[4] = {{0, 0}, {length, 0}, unfolded(2, 1), unfolded(3, -1)};
  Eigen::Matrix<Scalar, 2, 2> m = Eigen::Matrix<Scalar, 2, 2>::Zero();
  for (int i = 0; i < 4; ++i) m += 0.5 * hinge.k[std::size_t(i)] * p[i] * p[i].transpose();
  const Scalar a = m(0, 0), b = m(0, 1), c = m(1, 1);
  const Scalar squared = 0.25 * (a + c) * (a + c) + 0.5 * (0.25 * (a - c) * (a - c) + b * b);
  const Scalar areas = 0.5 * (e0.cross(x(2) - x(0)).norm() + e0.cross(x(3) - x(0)).norm());
  return {0.5 * squared, 0.5 * rigidity * areas / 3};
}

// Scales the hinges from `first` on so that, around every vertex, a bend stores B c^2 / 2 a
// square metre averaged over its directions: a vertex's calibration is the energy of the hinges
// on its edges over what they should store (hinge_bend_energy), a hinge's the mean of its
// edge's ends', and its weights are divided by the square root of it. An equilateral mesh's
// calibration is 1; only the triangles' shapes set it, never the bend or the rigidity.
void calibrate_hinges(Model& model, std::size_t first, Scalar rigidity) {
  std::vector<BendEnergy> around(model.initial_positions.size());  // summed over a vertex's edges' hinges
  for (std::size_t h = first; h < model.hinges.size(); ++h) {
    const BendEnergy e = hinge_bend_energy(model.hinges[h], model.initial_positions, rigidity);
    for (int end : {model.hinges[h].v[0], model.hinges[h].v[1]}) {
      around[std::size_t(end)].energy += e.energy;
      around[std::size_t(end)].expected += e.expected;
    }
  }
  for (std::size_t h = first; h < model.hinges.size(); ++h) {
    Hinge& hinge = model.hinges[h];
    const auto ratio = [&](int v) { return around[std::size_t(v)].energy / around[std::size_t(v)].expected; };
    const Scalar calibration = 0.5 * (ratio(hinge.v[0]) + ratio(hinge.v[1]));
    // Where the hinges at an edge's ends store nothing to compare (a calibration of zero, or
    // not finite beside a sliver of a triangle), the hinge keeps its weights as they are.
    if (!(calibration > 0 && std::isfinite(calibration))) continue;
    for (Scalar& k : hinge.k) k /= std::sqrt(calibration);
  }
}

// The hinges of a cloth's interior edges for bending rigidity B (N m), from its rest positions
// (Hinge): with e0 = x1 - x0, e1 = x2 - x0, e2 = x3 - x0, e3 = x2 - x1, e4 = x3 - x1 and cot(a, b)
// the cotangent of the angle between a and b, the weights (cot(-e0, e3) + cot(-e0, e4),
// cot(e0, e1) + cot(e0, e2), -cot(e0, e1) - cot(-e0, e3), -cot(e0, e2) - cot(-e0, e4)) (Bergou et
// al. 2006, section 4) times sqrt(B / (A1 + A2)): on a mesh of equilateral triangles, a bend
// of curvature c stores B c^2 / 2 a square metre. On other triangles it does not (the Cusick
// scene's discs, built ring by ring, stored 1.30-1.34 and 1.20 times it at 12.5 and 6 mm edges),
// so each hinge's weights are then divided by the square root of its calibration (calibrate_hinges).
void add_hinges(Model& model, const TriangleMesh& mesh, int offset, Scalar rigidity, Scalar damping_time) {
  if (!(rigidity > 0)) return;  // a scene pays only for what it asks for
  const auto cot = [](const Vec3& a, const Vec3& b) { return a.dot(b) / a.cross(b).norm(); };
  const std::size_t first = model.hinges.size();
  for (const auto& corners : hinges(mesh)) {
    Hinge hinge;
    for (int i = 0; i < 4; ++i) hinge.v[std::size_t(i)] = corners[std::size_t(i)] + offset;
    const auto x = [&](int i) -> const Vec3& { return model.initial_positions[std::size_t(hinge.v[std::size_t(i)])]; };
    const Vec3 e0 = x(1) - x(0), e1 = x(2) - x(0), e2 = x(3) - x(0), e3 = x(2) - x(1), e4 = x(3) - x(1);
    const Scalar c01 = cot(e0, e1), c02 = cot(e0, e2), c03 = cot(-e0, e3), c04 = cot(-e0, e4);
    const Scalar areas = 0.5 * (e0.cross(e1).norm() + e0.cross(e2).norm());
    const Scalar scale = std::sqrt(rigidity / areas);
    hinge.k = {scale * (c03 + c04), scale * (c01 + c02), -scale * (c01 + c03), -scale * (c02 + c04)};
    if (!std::all_of(hinge.k.begin(), hinge.k.end(), [](Scalar k) { return std::isfinite(k); })) continue;
    const Scalar largest = std::max({std::abs(hinge.k[0]), std::abs(hinge.k[1]), std::abs(hinge.k[2]), std::abs(hinge.k[3])});
    for (Scalar& k : hinge.k)
      if (std::abs(k) <= ZERO_HINGE_WEIGHT * largest) k = 0;
    hinge.damping = damping_time;
    model.hinges.push_back(hinge);
  }
  calibrate_hinges(model, first, rigidity);
}

// Memory a run of a scene needs, measured on drape_sphere.json at 64 x 64 and 128 x 128 quads
// with self-collision on (peak resident 103 MiB and 257 MiB): about 12.4 KiB a vertex, most
// of it the solver's factor, over a fixed part; rounded up. Fill-in grows faster than the
// vertex count, so this is a lower estimate for very large cloths.
constexpr double RUN_BYTES_FIXED = 64.0 * (1 << 20);
constexpr double RUN_BYTES_PER_VERTEX = 16.0 * 1024;

// Bytes the system can still give this process: MemAvailable of /proc/meminfo where there is
// one, else the physical memory.
double available_memory() {
  if (std::ifstream meminfo{"/proc/meminfo"}; meminfo) {
    std::string key;
    double kib = 0;
    std::string unit;
    while (meminfo >> key >> kib >> unit)
      if (key == "MemAvailable:") return kib * 1024;
  }
  return double(::sysconf(_SC_PHYS_PAGES)) * double(::sysconf(_SC_PAGESIZE));
}

// Refuses a scene whose cloths need more memory than the machine has, before anything large
// is allocated. Grids are counted from their resolution; a mesh cloth was read already.
void check_memory(const Scene& scene, double vertices) {
  const double needed = RUN_BYTES_FIXED + RUN_BYTES_PER_VERTEX * vertices;
  const double available = available_memory();
  if (needed <= available) return;
  char text[256];
  std::snprintf(text, sizeof text,
                "the cloths have %.0f vertices; a run needs about %.3g GiB of memory (16 KiB a vertex), more than "
                "the %.3g GiB this machine has available",
                vertices, needed / double(1 << 30), available / double(1 << 30));
  fail(scene, "/cloths", text);
}

// Every initial position finite and within MAX_COORDINATE: transforms of valid numbers can
// still leave a double's range or reach where a cloth's own size is below its rounding.
void check_positions(const Scene& scene, const std::vector<Vec3>& positions, std::size_t first, const std::string& path) {
  for (std::size_t v = first; v < positions.size(); ++v) {
    if (positions[v].allFinite() && positions[v].cwiseAbs().maxCoeff() <= MAX_COORDINATE) continue;
    std::ostringstream where;
    where << "vertex " << v - first << " lands at (" << positions[v].x() << ", " << positions[v].y() << ", "
          << positions[v].z() << "); expected finite coordinates within +-" << MAX_COORDINATE << " m";
    fail(scene, path, where.str());
  }
}

}  // namespace

Model build_model(const Scene& scene) {
  Model model;
  model.scene = scene;
  model.pin_of_vertex.clear();

  double grid_vertices = 0;
  for (const ClothSpec& spec : scene.cloths)
    if (spec.grid) grid_vertices += double(spec.grid->resolution[0] + 1) * double(spec.grid->resolution[1] + 1);
  check_memory(scene, grid_vertices);

  for (std::size_t c = 0; c < scene.cloths.size(); ++c) {
    const ClothSpec& spec = scene.cloths[c];
    const std::string path = "/cloths/" + std::to_string(c);
    // The projective solver's springs are fixed-weight constraints: one constant both ways.
    if (spec.material.compression < 1 && scene.solver.kind == SolverKind::Projective)
      fail(scene, path + "/material/compression",
           "the projective solver's springs resist compression as they resist stretching; expected the cholmod or "
           "cg solver for a 'compression' below 1");
    if (spec.material.membrane_triangles && scene.solver.kind == SolverKind::Projective)
      fail(scene, path + "/material/membrane",
           "the projective solver takes springs and hinges, not the membrane's triangles; expected the cholmod or cg "
           "solver for 'membrane' 'triangles', or 'springs'");
    std::optional<GridMesh> grid;
    TriangleMesh mesh;
    ClothRange range;
    if (spec.grid) {
      grid = make_grid(*spec.grid);
      mesh = grid->mesh;
    } else {
      mesh = read_mesh(scene, spec.mesh_file, path + "/mesh");
      // The cloth's vertices in the file's order: its frames list them so, and a handle's
      // nodes name them so.
      try {
        range.numbering_lost = !number_as_in_file(mesh, spec.mesh_file);
      } catch (const MeshFileError& e) {
        fail(scene, path + "/mesh", e.what());
      }
    }
    range.from_file = mesh.from_file;
    range.first_vertex = int(model.initial_positions.size());
    range.vertex_count = int(mesh.vertices.size());
    range.first_triangle = int(model.triangles.size());
    range.triangle_count = int(mesh.triangles.size());
    const int offset = range.first_vertex;
    for (const Vec3& v : mesh.vertices) model.initial_positions.push_back(spec.transform.apply(v));
    check_positions(scene, model.initial_positions, std::size_t(offset), path);
    model.masses.resize(model.initial_positions.size(), 0.0);
    model.air_damping.resize(model.initial_positions.size(), spec.material.air_damping);
    model.initial_velocities.resize(model.initial_positions.size(), spec.velocity);
    for (const Triangle& t : mesh.triangles) {
      const Triangle global{t[0] + offset, t[1] + offset, t[2] + offset};
      model.triangles.push_back(global);
      const Vec3& a = model.initial_positions[global[0]];
      const Scalar area = 0.5 * (model.initial_positions[global[1]] - a).cross(model.initial_positions[global[2]] - a).norm();
      for (int k = 0; k < 3; ++k) model.masses[global[k]] += spec.material.density * area / 3;
    }
    const Material& m = spec.material;
    // A bending rigidity names the hinge model; the bending springs are the other.
    const Scalar bend_springs = m.bending_rigidity > 0 ? 0 : m.bend;
    const bool fabric = m.tensile_stiffness > 0;  // the fabric's stiffnesses, or the springs'
    const std::size_t first_spring = model.springs.size();
    if (grid) {
      const GridSprings springs = grid_springs(*grid);
      if (fabric) {
        add_fabric_grid_springs(model, *grid, springs, offset, m, scene, path);
      } else {
        add_springs(model, springs.stretch, offset, m.stretch, m.damping, SpringKind::Stretch);
        add_springs(model, springs.shear, offset, m.shear, m.damping, SpringKind::Shear);
      }
      add_springs(model, springs.bend, offset, bend_springs, m.damping, SpringKind::Bend);
    } else {
      // The fabric's warp and weft: the mesh's own x and y axes after the cloth's transform.
      const Vec3 origin = spec.transform.apply(Vec3::Zero());
      const Vec3 warp = (spec.transform.apply(Vec3::UnitX()) - origin).normalized();
      const Vec3 weft = (spec.transform.apply(Vec3::UnitY()) - origin).normalized();
      if (fabric && m.membrane_triangles) {
        add_membranes(model, mesh, offset, m, warp, weft);
      } else if (fabric && m.shear_stiffness > 0) {
        add_fabric_mesh_springs(model, mesh, offset, m, warp, weft);
      } else if (fabric) {
        add_isotropic_mesh_springs(model, mesh, offset, m);
      } else {
        add_springs(model, mesh_edges(mesh), offset, m.stretch, m.damping, SpringKind::Stretch);
      }
      add_springs(model, bending_pairs(mesh), offset, bend_springs, m.damping, SpringKind::Bend);
    }
    Scalar diagonal_limit = 0;  // a grid's shear springs' (Material::shear_locking_angle)
    if (grid && m.shear_locking_angle > 0) {
      const auto [a, b] = cell_sides(model, *grid, offset);
      diagonal_limit = m.strain_limit * std::sqrt(1 + 2 * a * b * std::sin(m.shear_locking_angle * M_PI / 180) / (a * a + b * b));
    }
    for (std::size_t k = first_spring; k < model.springs.size(); ++k) {
      if (model.springs[k].kind == SpringKind::Stretch) model.springs[k].limit = m.strain_limit;
      if (model.springs[k].kind == SpringKind::Shear) model.springs[k].limit = diagonal_limit;
      model.springs[k].compression = m.compression;
    }
    // A grid, or a mesh laid out on one, bends by the grid's discrete Hessian (lattice_bending.h):
    // the hinges of right triangles bend half as stiffly along the cells' sides as along their
    // diagonals (docs/materials.md). Other meshes by their hinges.
    if (grid) {
      const auto [a, b] = cell_sides(model, *grid, offset);
      add_lattice_bending(model, grid_lattice(*grid, offset, a, b), m.bending_rigidity, m.damping);
      range.lattice_bending = m.bending_rigidity > 0;
    } else if (const auto lattice = m.bending_rigidity > 0 ? mesh_lattice(model, mesh, offset) : std::nullopt) {
      add_lattice_bending(model, *lattice, m.bending_rigidity, m.damping);
      range.lattice_bending = true;
    } else {
      add_hinges(model, mesh, offset, m.bending_rigidity, m.damping);
    }
    model.cloths.push_back(range);
  }

  if (double(model.vertex_count()) > grid_vertices) check_memory(scene, double(model.vertex_count()));

  // A thickness of a sizeable part of a cloth makes every vertex a contact of every other.
  for (std::size_t c = 0; c < model.cloths.size(); ++c) {
    const ClothRange& range = model.cloths[c];
    Vec3 lo = model.initial_positions[std::size_t(range.first_vertex)], hi = lo;
    for (int v = range.first_vertex; v < range.first_vertex + range.vertex_count; ++v)
      lo = lo.cwiseMin(model.initial_positions[std::size_t(v)]), hi = hi.cwiseMax(model.initial_positions[std::size_t(v)]);
    const Scalar limit = MAX_THICKNESS_OF_CLOTH * (hi - lo).norm();
    if (scene.collisions.thickness > limit) {
      std::ostringstream what;
      what << "the thickness (" << scene.collisions.thickness << " m) is more than a quarter of cloth " << c
           << "'s diagonal (" << (hi - lo).norm() << " m); expected at most " << limit << " m";
      fail(scene, "/collisions/thickness", what.str());
    }
  }

  // Handles: the pinned vertices.
  model.pin_of_vertex.assign(model.initial_positions.size(), -1);
  for (std::size_t h = 0; h < scene.handles.size(); ++h) {
    const HandleSpec& handle = scene.handles[h];
    const std::string path = "/handles/" + std::to_string(h);
    const ClothRange& range = model.cloths[handle.cloth];
    std::vector<int> chosen;
    for (std::size_t k = 0; k < handle.nodes.size(); ++k) {
      const int node = handle.nodes[k];
      const std::string at = path + "/nodes/" + std::to_string(k);
      if (range.numbering_lost)
        fail(scene, at, "cloth " + std::to_string(handle.cloth) + "'s mesh file gives a vertex in a form drape cannot match to "
                            "its 'v' line, so its numbering is not the file's; expected the vertices named by a 'box' or 'ball'");
      // A mesh read from an OBJ file: the file's vertex numbering (from 0), which may count
      // vertices no triangle uses.
      const int count = range.from_file.empty() ? range.vertex_count : int(range.from_file.size());
      if (node >= count)
        fail(scene, at, "vertex " + std::to_string(node) + " does not exist: cloth " + std::to_string(handle.cloth) + " has " +
                            std::to_string(count) + " vertices");
      const int vertex = range.from_file.empty() ? node : range.from_file[std::size_t(node)];
      if (vertex < 0)
        fail(scene, at, "vertex " + std::to_string(node) + " of cloth " + std::to_string(handle.cloth) +
                            "'s mesh file is used by no triangle, so it is not part of the cloth; expected a vertex of a triangle");
      chosen.push_back(range.first_vertex + vertex);
    }
    if (!handle.corners.empty()) {
      const auto& cloth = scene.cloths[handle.cloth];
      if (!cloth.grid) fail(scene, path + "/corners", "corner names need a grid cloth; use 'nodes', 'box' or 'ball' for a mesh");
      const GridMesh grid = make_grid(*cloth.grid);
      for (const std::string& name : handle.corners) chosen.push_back(range.first_vertex + *grid_corner(grid, name));
    }
    // The cloth's vertices whose initial positions a region (a box or a ball) holds.
    const auto choose_inside = [&](const auto& region, const std::string& key) {
      std::size_t found = 0;
      for (int v = range.first_vertex; v < range.first_vertex + range.vertex_count; ++v)
        if (region.contains(model.initial_positions[v])) chosen.push_back(v), ++found;
      if (found == 0) fail(scene, path + "/" + key, "the " + key + " holds no vertex of cloth " + std::to_string(handle.cloth));
    };
    if (handle.box) choose_inside(*handle.box, "box");
    if (handle.ball) choose_inside(*handle.ball, "ball");
    for (int v : chosen) {
      model.initial_velocities[v] = handle.motion.velocity_at(model.initial_positions[v], 0);
      if (model.pin_of_vertex[v] >= 0) continue;  // already pinned by an earlier handle
      model.pin_of_vertex[v] = int(model.pins.size());
      model.pins.push_back({v, int(h)});
    }
  }

  // Obstacles.
  for (std::size_t o = 0; o < scene.obstacles.size(); ++o) {
    Obstacle obstacle{scene.obstacles[o], {}};
    if (obstacle.spec.kind == ObstacleSpec::Kind::Mesh) {
      obstacle.mesh = read_mesh(scene, obstacle.spec.mesh_file, "/obstacles/" + std::to_string(o) + "/mesh");
      for (Vec3& v : obstacle.mesh.vertices) v = obstacle.spec.transform.apply(v);
      check_positions(scene, obstacle.mesh.vertices, 0, "/obstacles/" + std::to_string(o));
    }
    model.obstacles.push_back(std::move(obstacle));
  }

  // Bounds: given, or everything at the start grown by 100 diagonals.
  if (scene.bounds) {
    model.bounds = *scene.bounds;
    // The run stops as soon as a cloth vertex is outside the bounds, so a box that leaves out
    // a cloth's start would stop every run at its first step.
    for (std::size_t c = 0; c < model.cloths.size(); ++c) {
      const ClothRange& range = model.cloths[c];
      for (int v = range.first_vertex; v < range.first_vertex + range.vertex_count; ++v) {
        const Vec3& x = model.initial_positions[v];
        if (model.bounds.contains(x)) continue;
        std::ostringstream where;
        where << "expected a box holding every cloth's initial position; cloth " << c << " has a vertex at (" << x.x()
              << ", " << x.y() << ", " << x.z() << ") outside it";
        fail(scene, "/bounds", where.str());
      }
    }
  } else {
    const Box extent = initial_extent(model);
    const Scalar grow = 100 * std::max<Scalar>((extent.max - extent.min).norm(), 1e-3);
    model.bounds = Box{extent.min - Vec3::Constant(grow), extent.max + Vec3::Constant(grow)};
  }
  return model;
}

Box initial_extent(const Model& model) {
  Box box{model.initial_positions.front(), model.initial_positions.front()};
  const auto include = [&](const Vec3& p) { box.min = box.min.cwiseMin(p), box.max = box.max.cwiseMax(p); };
  for (const Vec3& p : model.initial_positions) include(p);
  for (const Obstacle& o : model.obstacles) {
    if (o.spec.kind == ObstacleSpec::Kind::Sphere)
      include(o.spec.center - Vec3::Constant(o.spec.radius)), include(o.spec.center + Vec3::Constant(o.spec.radius));
    for (const Vec3& p : o.mesh.vertices) include(p);
  }
  return box;
}

}  // namespace drape
