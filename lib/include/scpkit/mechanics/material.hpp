#pragma once
// Material cards (materials/*.toml): one per thread, with per-ply properties, moduli with
// source and uncertainty, and reference coil geometries. See docs/data-format.md.
#include <filesystem>
#include <string>
#include <vector>

#include "scpkit/mechanics/coil.hpp"

namespace scpkit {

struct ReferenceGeometry {
  int plies = 0;
  CoilGeometry coil;
  std::string source;
};

struct Material {
  std::string id;
  std::string name;
  std::string source;
  double linear_density_dtex = 0.0;  ///< per ply
  double density_kg_m3 = 0.0;
  double ply_diameter_m = 0.0;  ///< per ply
  Uncertain tensile_modulus_Pa;
  std::string tensile_modulus_source;
  Uncertain shear_modulus_Pa;
  std::string shear_modulus_source;
  std::vector<ReferenceGeometry> geometries;

  /// Solid cross-section of one ply, m^2: linear density / density.
  double ply_area_m2() const;
  /// Axial stiffness of a straight p-ply thread of the given length: E p A / l, N/m.
  double thread_stiffness(int plies, double length_m) const;
  /// The card's reference geometry for a ply count, or nullptr.
  const ReferenceGeometry* geometry_for(int plies) const;
};

/// Loads and validates a card. InputError names the file, line and column of the bad entry.
Material load_material(const std::filesystem::path& file);

/// Finds `id` (file materials/<id>.toml) in $SCPKIT_MATERIALS, ./materials, then the
/// source tree's materials/. InputError listing where it looked when absent.
Material find_material(const std::string& id);

}  // namespace scpkit
