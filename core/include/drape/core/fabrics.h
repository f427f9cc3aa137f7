#pragma once
/// \file
/// Fabric presets from published measurements (docs/materials.md).
///
/// Each preset is a fabric measured by Wang, Ramamoorthi and O'Brien ("Data-Driven Elastic
/// Models for Cloth: Modeling and Measurement", ACM Transactions on Graphics 30(4), 71, 2011),
/// as their data files for the ARCSim simulator give it, converted to the fabric's units of
/// drape's material (mass per area, tensile and shear stiffness, bending rigidity).

#include <array>
#include <string>
#include <vector>

#include "drape/core/scene.h"

namespace drape {

/// One fabric as its data file gives it: the numbers at zero strain and at the lowest
/// curvature, copied verbatim.
struct MeasuredFabric {
  std::string name;                ///< the data file's name, without ".json"
  std::string use, content;        ///< the data's README: typical use and fibre content
  Scalar density = 0;              ///< "density": kg/m^2
  /// "stretching", first row (zero strain): c0 .. c3 of the simulator's Green-strain energy
  /// density 1/2 k0 e_uu^2 + k1 e_uu e_vv + 1/2 k2 e_vv^2 + k3 e_uv^2, with k = 2 c (N/m; the
  /// simulator doubles the file's numbers and clamps negative ones to zero).
  std::array<Scalar, 4> stretching{};
  /// "bending", first column of its three rows (bending across 0, 45 and 90 degrees to the
  /// fabric's u axis, at the lowest curvature): the simulator's hinge constant ke (N m), whose
  /// hinge stores ke l^2 theta^2 / (8 (A0 + A1)) on an edge of length l between triangles of
  /// areas A0 and A1 bent by theta.
  std::array<Scalar, 3> bending{};
};

/// The measured fabrics drape offers as presets, in the order docs/materials.md lists them.
const std::vector<MeasuredFabric>& measured_fabrics();

/// The fabric named, or nullptr.
const MeasuredFabric* find_measured_fabric(const std::string& name);

/// Their names, in order, separated by commas (for messages).
std::string measured_fabric_names();

/// A measured fabric in drape's units.
struct FabricPreset {
  Scalar density = 0;            ///< kg/m^2
  Scalar tensile_stiffness = 0;  ///< N/m: the mean of the u and v directions' (each free to narrow)
  Scalar shear_stiffness = 0;    ///< N/m
  Scalar bending_rigidity = 0;   ///< N m: the mean over the three directions
};

/// The simulator's hinge constant times this is the bending rigidity: on a mesh of equilateral
/// triangles bent into a cylinder of curvature kappa, its hinges store (ke / 4) kappa^2 / 2 a
/// square metre in every direction of the bend (the continuum's B kappa^2 / 2; checked in
/// Fabric.TheMeasuredHingeConstantIsFourTimesTheRigidity).
inline constexpr Scalar HINGE_CONSTANT_TO_RIGIDITY = 0.25;

/// Converts a measured fabric: tensile stiffness along u is C11 - C12^2 / C22 with C = 2 c
/// (plane stress, the strip free to narrow), along v likewise, and drape's isotropic sheet takes
/// their mean; the shear stiffness is k3 / 2 = c3 (the energy k3 e_uv^2 with the shear angle
/// 2 e_uv); the bending rigidity is HINGE_CONSTANT_TO_RIGIDITY times the mean hinge constant.
FabricPreset fabric_preset(const MeasuredFabric& fabric);

/// Sets a material's fabric keys to the preset's: density, tensile and shear stiffness, bending
/// rigidity (on a grid and on a mesh alike).
void apply_fabric_preset(const MeasuredFabric& fabric, Material& material);

}  // namespace drape
