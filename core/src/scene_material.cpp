#include "drape/core/fabrics.h"

#include "scene_node.h"

namespace drape::scene_json {

void read_material(const Node& m, bool grid, Material& material) {
  m.allow({"preset", "density", "mass_per_area", "stretch", "tensile_stiffness", "shear", "shear_stiffness", "bend",
           "bending_rigidity", "damping", "air_damping", "strain_limit", "shear_locking_angle",
           "compression", "membrane"});
  // A preset is a measured fabric in the fabric's keys (fabrics.h); keys beside it override it.
  const MeasuredFabric* preset = m.has("preset") ? find_measured_fabric(m.at("preset").string()) : nullptr;
  if (m.has("preset") && !preset)
    m.at("preset").fail("expected a fabric preset: one of " + measured_fabric_names() + " (docs/materials.md)");
  if (preset) apply_fabric_preset(*preset, material);
  // A material is the springs' constants or the fabric's measurements, not a mix: a spring
  // key beside the fabric's stiffnesses would be silently ignored or (bend springs) stiffen
  // the sheet by an amount that depends on the resolution.
  if (m.has("density") && m.has("mass_per_area"))
    m.at("mass_per_area").fail("expected 'density' (kg/m^2) or 'mass_per_area' (g/m^2), not both");
  const bool fabric = preset || m.has("tensile_stiffness") || m.has("shear_stiffness");
  for (const char* spring : {"stretch", "shear", "bend"})
    if (fabric && m.has(spring))
      m.at(spring).fail(std::string("expected no '") + spring + "' beside " +
                        (preset ? "a 'preset'" : "'tensile_stiffness' and 'shear_stiffness' (N/m)") +
                        ": the fabric's keys set the springs, and its bending is 'bending_rigidity' (N m)");
  if (!grid && !preset && m.has("shear_stiffness") && !m.has("tensile_stiffness"))
    m.at("shear_stiffness").fail("expected 'tensile_stiffness' (N/m) beside it: a mesh's edge springs are fitted to both");
  if (grid && fabric && !preset && !(m.has("tensile_stiffness") && m.has("shear_stiffness")))
    m.at(m.has("tensile_stiffness") ? "tensile_stiffness" : "shear_stiffness")
        .fail("expected 'tensile_stiffness' and 'shear_stiffness' together (N/m): a grid's springs need both");
  if (m.has("bend") && m.has("bending_rigidity"))
    m.at("bending_rigidity").fail("expected one bending model: 'bend' (springs) or 'bending_rigidity' (N m, hinges), not both");
  if (m.has("density")) material.density = m.at("density").up_to(MAX_AREAL_DENSITY, "kg/m^2");
  if (m.has("mass_per_area")) material.density = m.at("mass_per_area").up_to(1000 * MAX_AREAL_DENSITY, "g/m^2") / 1000;
  if (m.has("tensile_stiffness")) material.tensile_stiffness = m.at("tensile_stiffness").up_to(MAX_STIFFNESS, "N/m");
  if (m.has("shear_stiffness")) material.shear_stiffness = m.at("shear_stiffness").up_to(MAX_STIFFNESS, "N/m");
  if (fabric) material.bend = 0;  // bending, if any, from the rigidity
  if (m.has("stretch")) material.stretch = m.at("stretch").up_to(MAX_STIFFNESS, "N", true);
  if (m.has("shear") && !grid)
    m.at("shear").fail("a mesh cloth's springs are its edges ('stretch') and the pairs across them ('bend'): it has no "
                       "shear springs; expected no 'shear' on a mesh cloth (or the fabric's 'tensile_stiffness' and "
                       "'shear_stiffness', N/m, to which its edge springs are fitted)");
  if (m.has("shear")) material.shear = m.at("shear").up_to(MAX_STIFFNESS, "N", true);
  if (m.has("bend")) material.bend = m.at("bend").up_to(MAX_STIFFNESS, "N", true);
  if (m.has("bending_rigidity"))  // no bending: `bend` 0
    material.bending_rigidity = m.at("bending_rigidity").up_to(MAX_BENDING_RIGIDITY, "N m");
  if (m.has("damping")) material.damping = m.at("damping").up_to(MAX_DAMPING, "s", true);
  if (m.has("air_damping")) material.air_damping = m.at("air_damping").up_to(MAX_DAMPING, "1/s", true);
  if (m.has("strain_limit"))
    material.strain_limit = m.at("strain_limit").number_in(MIN_STRAIN_LIMIT, MAX_STRAIN_LIMIT, "from 1.001 to 10");
  if (m.has("shear_locking_angle")) {
    const Node angle = m.at("shear_locking_angle");
    if (!grid)
      angle.fail("a mesh cloth has no shear springs: its edges' 'strain_limit' bounds its shear too; expected no "
                 "'shear_locking_angle' on a mesh cloth");
    if (!(material.strain_limit > 0))
      angle.fail("expected a 'strain_limit' beside it: the diagonals' limit is the length they reach at the angle with "
                 "the cell's sides at the strain limit");
    material.shear_locking_angle = angle.up_to(MAX_SHEAR_LOCKING_ANGLE, "degrees");
  }
  if (m.has("compression")) material.compression = m.at("compression").number_in(0, 1, "from 0 to 1");
  if (m.has("membrane")) {
    const Node node = m.at("membrane");
    const std::string kind = node.string();
    if (kind != "springs" && kind != "triangles")
      node.fail("expected 'springs' (edge springs fitted to each triangle) or 'triangles' (constant strain elements)");
    material.membrane_triangles = kind == "triangles";
    if (material.membrane_triangles) {
      if (grid)
        node.fail("a grid's springs hold the fabric's tension and shear exactly; expected 'triangles' on a mesh cloth only");
      if (!(material.tensile_stiffness > 0 && material.shear_stiffness > 0))
        node.fail("expected a fabric's 'tensile_stiffness' and 'shear_stiffness' (N/m, or a 'preset') for the triangles");
      if (material.strain_limit > 0)
        m.at("strain_limit").fail("the strain limit holds edge springs; expected no 'strain_limit' with 'membrane' 'triangles'");
      if (material.compression < 1)
        m.at("compression").fail("the triangles resist compression as stretching; expected no 'compression' with "
                                 "'membrane' 'triangles'");
    }
  }
}

}  // namespace drape::scene_json
