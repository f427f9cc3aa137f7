#include "drape/core/fabrics.h"

#include <algorithm>
#include <cassert>

namespace drape {

const std::vector<MeasuredFabric>& measured_fabrics() {
  // Copied from the data files of Wang, Ramamoorthi and O'Brien 2011 as distributed for ARCSim
  // (materials/<name>.json; read at github.com/wxhaooo/lyra, commit 5158f74), with the README
  // that names each one's use and content. docs/materials.md has the conversion and the caveats.
  static const std::vector<MeasuredFabric> fabrics = {
      {"11oz-black-denim", "jeans", "99% cotton, 1% spandex", 0.324,
       {205.352005, 10.234077, 1013.88629, 53.387184}, {64.196457e-6, 73.384567e-6, 96.951576e-6}},
      {"royal-target", "pants", "65% cotton, 35% polyester", 0.220,
       {2016.55456, 9.170511, 2034.97644, 104.759674}, {125.409805e-6, 107.997696e-6, 125.409805e-6}},
      {"white-dots-on-blk", "tablecloth", "100% polyester", 0.128,
       {2002.08618, 0.345588, 2027.48559, 19.189022}, {51.713814e-6, 40.659470e-6, 31.282822e-6}},
      {"gray-interlock", "t-shirt", "60% cotton, 40% polyester", 0.187,
       {16.593832, -14.695990, 34.477123, 36.860302}, {23.191698e-6, 24.749964e-6, 14.267624e-6}},
      {"navy-sparkle-sweat", "sweater", "96% polyester, 4% spandex", 0.224,
       {12.486332, -19.875324, 3.272434, 17.616289}, {59.469658e-6, 40.072277e-6, 45.625023e-6}},
  };
  return fabrics;
}

const MeasuredFabric* find_measured_fabric(const std::string& name) {
  const auto& all = measured_fabrics();
  const auto it = std::find_if(all.begin(), all.end(), [&](const MeasuredFabric& f) { return f.name == name; });
  return it == all.end() ? nullptr : &*it;
}

std::string measured_fabric_names() {
  std::string names;
  for (const MeasuredFabric& f : measured_fabrics()) names += (names.empty() ? "" : ", ") + f.name;
  return names;
}

FabricPreset fabric_preset(const MeasuredFabric& fabric) {
  // The simulator's moduli: twice the file's numbers, negative ones clamped to zero.
  const auto k = [&](int i) { return 2 * std::max(Scalar(0), fabric.stretching[std::size_t(i)]); };
  const Scalar c11 = k(0), c12 = k(1), c22 = k(2);
  assert(c11 > 0 && c22 > 0 && c12 * c12 < c11 * c22 && "a measured fabric's moduli are positive definite");
  FabricPreset p;
  p.density = fabric.density;
  p.tensile_stiffness = 0.5 * ((c11 - c12 * c12 / c22) + (c22 - c12 * c12 / c11));
  p.shear_stiffness = k(3) / 2;
  p.bending_rigidity = HINGE_CONSTANT_TO_RIGIDITY * (fabric.bending[0] + fabric.bending[1] + fabric.bending[2]) / 3;
  return p;
}

void apply_fabric_preset(const MeasuredFabric& fabric, Material& material) {
  const FabricPreset p = fabric_preset(fabric);
  material.density = p.density;
  material.tensile_stiffness = p.tensile_stiffness;
  material.shear_stiffness = p.shear_stiffness;
  material.bending_rigidity = p.bending_rigidity;
}

}  // namespace drape
