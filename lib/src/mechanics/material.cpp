#include "scpkit/mechanics/material.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>

#include "../io/toml_reader.hpp"
#include "scpkit/error.hpp"

namespace scpkit {

double Material::ply_area_m2() const { return linear_density_dtex * 1e-7 / density_kg_m3; }

double Material::thread_stiffness(int plies, double length_m) const {
  if (plies < 1 || !(length_m > 0.0))
    throw_invalid("thread stiffness needs plies >= 1 and length > 0");
  return tensile_modulus_Pa.value * plies * ply_area_m2() / length_m;
}

const ReferenceGeometry* Material::geometry_for(int plies) const {
  for (const auto& g : geometries) {
    if (g.plies == plies) return &g;
  }
  return nullptr;
}

Material load_material(const std::filesystem::path& file) {
  using detail::TomlReader;
  const std::string name = file.string();
  const toml::table root = TomlReader::parse(file);
  const TomlReader r(name);
  r.only_keys(root,
              {"id", "name", "source", "ply", "tensile_modulus", "shear_modulus", "geometry"});
  Material m;
  m.id = r.text(root, "id", "", true);
  m.name = r.text(root, "name", "", true);
  m.source = r.text(root, "source", "");
  const toml::table& ply = *r.table(root, "ply", true);
  r.only_keys(ply, {"linear_density_dtex", "density_g_cm3", "diameter_mm"});
  m.linear_density_dtex = r.positive(ply, "linear_density_dtex");
  m.density_kg_m3 = r.positive(ply, "density_g_cm3") * 1000.0;
  m.ply_diameter_m = r.positive(ply, "diameter_mm") * 1e-3;
  auto modulus = [&](const char* key, std::string& source) {
    const toml::table& t = *r.table(root, key, true);
    r.only_keys(t, {"value_GPa", "sigma_GPa", "source"});
    source = r.text(t, "source", "", true);
    return Uncertain{r.positive(t, "value_GPa") * 1e9,
                     r.number(t, "sigma_GPa", 0.0, 0.0, true) * 1e9};
  };
  m.tensile_modulus_Pa = modulus("tensile_modulus", m.tensile_modulus_source);
  m.shear_modulus_Pa = modulus("shear_modulus", m.shear_modulus_source);
  if (const toml::node* g = root.get("geometry")) {
    const toml::array* arr = g->as_array();
    if (!arr) r.fail(g, "'geometry' must be an array of tables ([[geometry]])");
    for (const toml::node& item : *arr) {
      const toml::table* t = item.as_table();
      if (!t) r.fail(&item, "each [[geometry]] entry must be a table");
      r.only_keys(*t, {"plies", "d_mm", "D_mm", "n", "legs", "length_mm", "source"});
      ReferenceGeometry rg;
      rg.plies = static_cast<int>(r.integer(*t, "plies", 0, 1, 1000));
      if (rg.plies == 0) r.fail(t, "missing key 'plies'");
      rg.coil.wire_d_m = r.positive(*t, "d_mm") * 1e-3;
      rg.coil.mean_D_m = r.positive(*t, "D_mm") * 1e-3;
      rg.coil.coils = r.positive(*t, "n");
      rg.coil.legs = static_cast<int>(r.integer(*t, "legs", 1, 1, 2));
      rg.coil.length_m = r.positive(*t, "length_mm", 0.0, false) * 1e-3;
      rg.source = r.text(*t, "source", "");
      try {
        rg.coil.validate();
      } catch (const InvalidArgument& e) {
        r.fail(t, e.what());
      }
      m.geometries.push_back(rg);
    }
  }
  if (m.id != file.stem().string()) {
    r.fail(root.get("id"), fmt::format("id '{}' does not match the file name '{}'", m.id,
                                       file.filename().string()));
  }
  return m;
}

Material find_material(const std::string& id) {
  std::vector<std::filesystem::path> dirs;
  if (const char* env = std::getenv("SCPKIT_MATERIALS")) dirs.emplace_back(env);
  dirs.emplace_back("materials");
  dirs.emplace_back(std::filesystem::path(SCPKIT_SOURCE_DIR) / "materials");
  std::string looked;
  for (const auto& d : dirs) {
    const auto f = d / (id + ".toml");
    if (std::filesystem::exists(f)) return load_material(f);
    looked += (looked.empty() ? "" : ", ") + d.string();
  }
  throw InputError(id, 0, 0, fmt::format("no material card '{}.toml' in {}", id, looked));
}

}  // namespace scpkit
