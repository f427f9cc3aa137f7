#pragma once
// The sheet's in-plane stiffness measured as the fabric tests measure it (test_fabric.cpp,
// test_membrane.cpp): a model's strain energy under a homogeneous map of its rest positions in
// its plane, and the three small maps that read a sheet's shear and tension.
#include <cmath>
#include <string>

#include "drape/core/integrator.h"

namespace drape::testing {

inline Model model_of(const std::string& json) { return build_model(parse_scene(json, "inline.json")); }

/// The model's potential energy with its rest positions mapped by x -> F x in the plane z = 0
/// (the scenes here have no gravity and no bending: the strain energy of the springs or
/// triangles).
inline Scalar strain_energy(const Model& model, const Eigen::Matrix<Scalar, 2, 2>& map) {
  State state = initial_state(model);
  for (Vec3& x : state.positions) {
    const Eigen::Matrix<Scalar, 2, 1> p = map * Eigen::Matrix<Scalar, 2, 1>(x.x(), x.y());
    x = Vec3(p.x(), p.y(), x.z());
  }
  return potential_energy(model, state);
}

/// For a sheet of tensile stiffness T and shear stiffness G (N/m, the grid's sheet: c11 = c22
/// = s, c12 = c66 = G), at a strain e: a shear angle e, which stores G e^2 / 2 a square metre,
/// and stretches e along x and along y with the sheet's own narrowing (Poisson's ratio G / s),
/// each of which stores T e^2 / 2.
struct SheetStrains {
  Eigen::Matrix<Scalar, 2, 2> shear, along_x, along_y;
};
inline SheetStrains sheet_strains(Scalar T, Scalar G, Scalar e) {
  const Scalar s = 0.5 * (T + std::sqrt(T * T + 4 * G * G)), nu = G / s;
  SheetStrains out;
  out.shear << 1, e, 0, 1;
  out.along_x << 1 + e, 0, 0, 1 - nu * e;
  out.along_y << 1 - nu * e, 0, 0, 1 + e;
  return out;
}

}  // namespace drape::testing
