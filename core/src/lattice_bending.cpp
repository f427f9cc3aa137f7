#include "lattice_bending.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <map>

#include <Eigen/Dense>

namespace drape {
namespace {

// A unit cell's triangle counts an eighth of the cell at each corner on its hypotenuse and a
// quarter at its right angle (the quarter squares about its corners, the diagonal halving two).
constexpr int DIAGONAL_CORNER_EIGHTHS = 1, RIGHT_ANGLE_EIGHTHS = 2;

}  // namespace

Lattice grid_lattice(const GridMesh& grid, int offset, Scalar a, Scalar b) {
  Lattice lattice;
  lattice.a = a;
  lattice.b = b;
  lattice.columns = grid.spec.resolution[0];
  lattice.rows = grid.spec.resolution[1];
  const std::size_t points = std::size_t(lattice.columns + 1) * std::size_t(lattice.rows + 1);
  lattice.vertex.resize(points);
  lattice.eighths.resize(points);
  lattice.along_i.assign(points, 1);
  lattice.along_j.assign(points, 1);
  lattice.whole_cell.assign(points, 1);
  for (int j = 0; j <= lattice.rows; ++j)
    for (int i = 0; i <= lattice.columns; ++i) {
      const std::size_t p = std::size_t(lattice.point(i, j));
      lattice.vertex[p] = grid.index(i, j) + offset;
      // Each of the (up to four) whole cells about the point gives it a quarter.
      const int cells = (i > 0 && j > 0) + (i < lattice.columns && j > 0) + (i > 0 && j < lattice.rows) +
                        (i < lattice.columns && j < lattice.rows);
      lattice.eighths[p] = 2 * cells;
      if (i == lattice.columns) lattice.along_i[p] = 0;
      if (j == lattice.rows) lattice.along_j[p] = 0;
      if (i == lattice.columns || j == lattice.rows) lattice.whole_cell[p] = 0;
    }
  return lattice;
}

std::optional<Lattice> mesh_lattice(const Model& model, const TriangleMesh& mesh, int offset) {
  if (mesh.triangles.empty()) return std::nullopt;
  const auto x = [&](int v) -> const Vec3& { return model.initial_positions[std::size_t(v + offset)]; };
  // The axes: the first triangle's legs at its right angle.
  const Triangle& first = mesh.triangles.front();
  int corner = -1;
  Vec3 leg_i, leg_j;
  for (int c = 0; c < 3 && corner < 0; ++c) {
    const Vec3 e1 = x(first[std::size_t((c + 1) % 3)]) - x(first[std::size_t(c)]);
    const Vec3 e2 = x(first[std::size_t((c + 2) % 3)]) - x(first[std::size_t(c)]);
    if (std::abs(e1.dot(e2)) <= AXES_TOLERANCE * e1.norm() * e2.norm()) corner = c, leg_i = e1, leg_j = e2;
  }
  if (corner < 0) return std::nullopt;
  Lattice lattice;
  lattice.a = leg_i.norm();
  lattice.b = leg_j.norm();
  if (!(lattice.a > 0 && lattice.b > 0)) return std::nullopt;
  // Each vertex's lattice point, rounded from the first triangle's legs; then the lattice
  // fitted to all of them (least squares: x = o + i A + j B), since one triangle's legs, read
  // in single precision, are off by a few millionths and the error grows along the rows.
  const Vec3 u0 = leg_i / lattice.a, w0 = leg_j / lattice.b;
  const Vec3 origin0 = x(first[std::size_t(corner)]);
  std::vector<std::array<long, 2>> ij(mesh.vertices.size());
  std::vector<char> used(mesh.vertices.size(), 0);
  for (const Triangle& t : mesh.triangles)
    for (int v : t) used[std::size_t(v)] = 1;
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d moments = Eigen::Matrix3d::Zero();  // rows: 1, i, j; columns: x, y, z
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (!used[v]) continue;
    const Vec3 r = x(int(v)) - origin0;
    const Scalar fi = r.dot(u0) / lattice.a, fj = r.dot(w0) / lattice.b;
    if (!(std::abs(fi) < 1e9 && std::abs(fj) < 1e9)) return std::nullopt;
    ij[v] = {std::lround(fi), std::lround(fj)};
    const Eigen::Vector3d basis(1, Scalar(ij[v][0]), Scalar(ij[v][1]));
    normal += basis * basis.transpose();
    moments += basis * r.transpose();
  }
  const Eigen::Matrix3d fit = normal.ldlt().solve(moments);  // rows: o - origin0, A, B
  const Vec3 offset_fit = fit.row(0).transpose(), along_i = fit.row(1).transpose(), along_j = fit.row(2).transpose();
  lattice.a = along_i.norm();
  lattice.b = along_j.norm();
  if (!(lattice.a > 0 && lattice.b > 0 && fit.allFinite()) ||
      std::abs(along_i.dot(along_j)) > LATTICE_TOLERANCE * lattice.a * lattice.b)
    return std::nullopt;
  const Scalar tolerance = LATTICE_TOLERANCE * std::min(lattice.a, lattice.b);
  // Each vertex's point again on the fitted lattice (the first rounding used one triangle's
  // axes), then how far it lies from it.
  const Eigen::Matrix<Scalar, 3, 2> axes = (Eigen::Matrix<Scalar, 3, 2>() << along_i, along_j).finished();
  const Eigen::Matrix<Scalar, 2, 3> project = (axes.transpose() * axes).inverse() * axes.transpose();
  long min_i = 0, min_j = 0, max_i = 0, max_j = 0;
  bool any = false;
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (!used[v]) continue;
    const Vec3 r = x(int(v)) - origin0 - offset_fit;
    const Eigen::Matrix<Scalar, 2, 1> f = project * r;
    ij[v] = {std::lround(f[0]), std::lround(f[1])};
    const auto [i, j] = ij[v];
    if ((r - Scalar(i) * along_i - Scalar(j) * along_j).norm() > tolerance) return std::nullopt;
    min_i = any ? std::min(min_i, i) : i, max_i = any ? std::max(max_i, i) : i;
    min_j = any ? std::min(min_j, j) : j, max_j = any ? std::max(max_j, j) : j;
    any = true;
  }
  const long columns = max_i - min_i, rows = max_j - min_j;
  if ((columns + 1) * (rows + 1) > 64 * long(mesh.vertices.size()) + 64) return std::nullopt;  // a sparse lattice: not a grid's layout
  lattice.columns = int(columns);
  lattice.rows = int(rows);
  const std::size_t points = std::size_t(columns + 1) * std::size_t(rows + 1);
  lattice.vertex.assign(points, -1);
  lattice.eighths.assign(points, 0);
  lattice.along_i.assign(points, 0);
  lattice.along_j.assign(points, 0);
  lattice.whole_cell.assign(points, 0);
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (!used[v]) continue;
    ij[v] = {ij[v][0] - min_i, ij[v][1] - min_j};
    int& at = lattice.vertex[std::size_t(lattice.point(int(ij[v][0]), int(ij[v][1])))];
    if (at >= 0) return std::nullopt;  // two vertices at one point
    at = int(v) + offset;
  }
  // Every triangle half of a cell: three of its corners, its legs along the axes.
  std::map<int, std::array<int, 4>> cell_corners;  // cell (its lowest point) -> how often each corner is used
  std::vector<int> triangles_in(points, 0);
  for (const Triangle& t : mesh.triangles) {
    std::array<std::array<long, 2>, 3> c;
    for (std::size_t k = 0; k < 3; ++k) c[k] = ij[std::size_t(t[k])];
    const long ci = std::min({c[0][0], c[1][0], c[2][0]}), cj = std::min({c[0][1], c[1][1], c[2][1]});
    std::array<int, 4> used_corners{};
    for (std::size_t k = 0; k < 3; ++k) {
      const long di = c[k][0] - ci, dj = c[k][1] - cj;
      if (di > 1 || dj > 1) return std::nullopt;
      if (++used_corners[std::size_t(2 * dj + di)] > 1) return std::nullopt;
    }
    const int cell = lattice.point(int(ci), int(cj));
    if (++triangles_in[std::size_t(cell)] > 2) return std::nullopt;
    auto& counts = cell_corners[cell];
    for (std::size_t k = 0; k < 4; ++k) counts[k] += used_corners[k];
    // Its legs are the unit edges; its right angle the corner with a leg along each axis.
    for (std::size_t k = 0; k < 3; ++k) {
      const auto& p = c[k];
      const auto& q = c[(k + 1) % 3];
      const long di = std::labs(p[0] - q[0]), dj = std::labs(p[1] - q[1]);
      const std::array<long, 2> low{std::min(p[0], q[0]), std::min(p[1], q[1])};
      if (di == 1 && dj == 0) lattice.along_i[std::size_t(lattice.point(int(low[0]), int(low[1])))] = 1;
      if (di == 0 && dj == 1) lattice.along_j[std::size_t(lattice.point(int(low[0]), int(low[1])))] = 1;
    }
    for (std::size_t k = 0; k < 3; ++k) {
      const auto& p = c[k];
      const auto& q = c[(k + 1) % 3];
      const auto& r = c[(k + 2) % 3];
      const bool right = (q[1] == p[1] && r[0] == p[0]) || (q[0] == p[0] && r[1] == p[1]);  // a leg along each axis
      lattice.eighths[std::size_t(lattice.point(int(p[0]), int(p[1])))] += right ? RIGHT_ANGLE_EIGHTHS : DIAGONAL_CORNER_EIGHTHS;
    }
  }
  // A cell with two triangles: they cover it, sharing a diagonal (each corner used, the
  // diagonal's twice).
  for (const auto& [cell, counts] : cell_corners) {
    if (triangles_in[std::size_t(cell)] < 2) continue;
    const bool covers = std::all_of(counts.begin(), counts.end(), [](int k) { return k >= 1; }) &&
                        ((counts[0] == 2 && counts[3] == 2) || (counts[1] == 2 && counts[2] == 2));
    if (!covers) return std::nullopt;
    lattice.whole_cell[std::size_t(cell)] = 1;
  }
  return lattice;
}

void add_lattice_bending(Model& model, const Lattice& lattice, Scalar rigidity, Scalar damping_time) {
  if (!(rigidity > 0)) return;  // a scene pays only for what it asks for
  const Scalar a = lattice.a, b = lattice.b;
  const int n = lattice.columns, m = lattice.rows;
  const auto vertex = [&](int i, int j) { return lattice.vertex[std::size_t(lattice.point(i, j))]; };
  const auto add = [&](std::array<int, 4> v, std::array<Scalar, 4> k) {
    Hinge hinge;
    hinge.v = v;
    hinge.k = k;
    hinge.damping = damping_time;
    model.hinges.push_back(hinge);
  };
  // A second difference of step h about point (i, j) from (i - di, j - dj) to (i + di, j + dj),
  // where both edges are the cloth's: the stencil's fourth corner unused.
  const auto second_difference = [&](int i, int j, int di, int dj, Scalar h) {
    const std::vector<char>& along = di ? lattice.along_i : lattice.along_j;
    if (!along[std::size_t(lattice.point(i - di, j - dj))] || !along[std::size_t(lattice.point(i, j))]) return;
    const Scalar area = a * b * (lattice.eighths[std::size_t(lattice.point(i, j))] / 8.0);
    const Scalar s = std::sqrt(rigidity * area) / (h * h);
    const int c = vertex(i, j);
    add({vertex(i - di, j - dj), c, vertex(i + di, j + dj), c}, {s, -2 * s, s, 0});
  };
  for (int j = 0; j <= m; ++j)
    for (int i = 1; i < n; ++i) second_difference(i, j, 1, 0, a);
  for (int i = 0; i <= n; ++i)
    for (int j = 1; j < m; ++j) second_difference(i, j, 0, 1, b);
  const Scalar twist = std::sqrt(2 * rigidity * a * b) / (a * b);
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i)
      if (lattice.whole_cell[std::size_t(lattice.point(i, j))])
        add({vertex(i, j), vertex(i + 1, j), vertex(i, j + 1), vertex(i + 1, j + 1)}, {twist, -twist, -twist, twist});
}

}  // namespace drape
