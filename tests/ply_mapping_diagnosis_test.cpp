// Ply-mapping diagnosis on rig pairs whose truth departs from what the file states in one known
// way: the SCP's legs, its active coils, or a coil whose effective coil count carries the
// direct-shear factor. The diagnosis must name that cause, and nothing on a faithful file.
#include "scpkit/diagnosis/ply_mapping_diagnosis.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "scpkit/error.hpp"
#include "scpkit/rig/rig.hpp"

namespace scpkit {
namespace {

const Material& card() {
  static const Material m = find_material("nylon-110-34-dtex");
  return m;
}

std::vector<double> column(const RigRun& r, const std::string& name, double scale) {
  const auto c = static_cast<std::size_t>(std::find(r.columns.begin(), r.columns.end(), name) -
                                          r.columns.begin());
  std::vector<double> v;
  for (const auto& row : r.rows) v.push_back(row.at(c) * scale);
  return v;
}

// A pair test of `plies` whose true coil is `truth`, described to the diagnosis as `stated`.
PlyMappingDiagnosis run(int plies, const CoilGeometry& truth, const CoilGeometry& stated,
                        std::uint64_t seed) {
  RigSpec s;
  s.seed = seed;
  s.plies = plies;
  s.specimen = "pair";
  s.coil = truth;
  const RigRun r = run_rig(s, card());
  PlyMappingData d;
  d.load_N = column(r, "load_g", 9.80665e-3);
  d.thread_strain = column(r, "thread_strain_pct", 0.01);
  d.scp_strain = column(r, "scp_strain_pct", 0.01);
  d.plies = plies;
  d.length_m = s.length_mm * 1e-3;
  d.coil = stated;
  return diagnose_ply_mapping(d, card());
}

CoilGeometry table1(int plies) { return card().geometry_for(plies)->coil; }

TEST(PlyMappingDiagnosis, FaithfulFilesNameNothingAndPredictTheGain) {
  for (int plies : {2, 4, 6}) {
    for (std::uint64_t seed : {1u, 2u}) {
      const PlyMappingDiagnosis d = run(plies, table1(plies), table1(plies), seed);
      EXPECT_EQ(d.cause, "none") << plies << " plies, seed " << seed;
      EXPECT_NEAR(d.miss_pct, 0.0, 2.0);
      // The prediction recomputed by hand: K_thr / K_SCP.
      const CoilGeometry c = table1(plies);
      const double k_thr = card().tensile_modulus_Pa.value * plies * card().ply_area_m2() / 0.1;
      const double k_scp = c.legs * c.legs * card().shear_modulus_Pa.value *
                           std::pow(c.wire_d_m, 4) / (8.0 * c.coils * std::pow(c.mean_D_m, 3));
      EXPECT_NEAR(d.predicted_gain.value, k_thr / k_scp, 1e-9 * k_thr / k_scp);
      ASSERT_EQ(d.candidates.size(), 5u);
      EXPECT_EQ(d.candidates.front().cause, "physics");
    }
  }
}

TEST(PlyMappingDiagnosis, NamesTheLegsWhenTheFileMiscountsThem) {
  for (int plies : {2, 4}) {
    CoilGeometry truth = table1(plies), stated = truth;
    truth.legs = 1;  // one leg of all the coils, described as double-backed
    const PlyMappingDiagnosis d = run(plies, truth, stated, 3);
    EXPECT_EQ(d.cause, "legs") << plies;
    EXPECT_NEAR(d.miss_pct, 300.0, 10.0);  // K falls by legs^2 = 4
  }
}

TEST(PlyMappingDiagnosis, NamesActiveCoilsWhenFewerCoilsDeflect) {
  for (double fraction : {0.75, 0.85}) {
    CoilGeometry truth = table1(4), stated = truth;
    truth.coils = fraction * stated.coils;
    const PlyMappingDiagnosis d = run(4, truth, stated, 4);
    EXPECT_EQ(d.cause, "active_coils") << fraction;
    EXPECT_NEAR(d.measured_gain / d.predicted_gain.value, fraction, 0.02);
  }
}

TEST(PlyMappingDiagnosis, NamesTheSpringIndexWhenTheDirectShearTermIsThere) {
  // A truth softer by exactly Wahl's direct-shear factor 1 + 1/(2 C^2) (as more coils).
  for (int plies : {2, 6}) {
    CoilGeometry truth = table1(plies), stated = truth;
    const double C = stated.spring_index();
    truth.coils = stated.coils * (1.0 + 1.0 / (2.0 * C * C));
    const PlyMappingDiagnosis d = run(plies, truth, stated, 5);
    EXPECT_EQ(d.cause, "spring_index") << plies;
  }
}

TEST(PlyMappingDiagnosis, RefusesTooLittleData) {
  PlyMappingData d;
  d.coil = table1(2);
  d.load_N.assign(10, 1.0);
  d.thread_strain.assign(10, 0.0);
  d.scp_strain.assign(10, 0.0);
  EXPECT_THROW(diagnose_ply_mapping(d, card()), IdentificationError);
  d.scp_strain.pop_back();
  EXPECT_THROW(diagnose_ply_mapping(d, card()), InvalidArgument);
}

}  // namespace
}  // namespace scpkit
