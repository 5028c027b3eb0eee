#pragma once
// Ply-mapping diagnosis: how well the helical-spring physics predicts an SCP actuator from its
// thread, and which of the causes PHYSICS.md section 2 lists explains the miss.
//
// Given paired thread and SCP strains under one load sequence (a "pair" test), the material
// card and the SCP's coil geometry:
//   predicted  g = K_thr / K_SCP,  K_thr = E q A / l,  K_SCP = legs^2 G d^4 / (8 n D^3)
//   measured   g from the paired strains (least squares, all readings)
// and, held out by blocks of whole cycles (each block predicted from the others), the SCP
// strain predicted from the measured thread strain by each candidate mapping:
//   physics        eps_SCP = g eps_thr + c                         (c from the training rows)
//   spring_index   g (1 + 1 / (2 C^2))   (Wahl's direct-shear term: spring index C = D/d < ~3)
//   legs           g legs^2 / legs'^2    (the actuator double-backed or not, against the file)
//   active_coils   g n_a / n, n_a fitted (end coils that do not deflect)
//   input_scale    eps_SCP = g Gamma[lambda F] + c, Gamma the thread's Preisach operator,
//                  lambda and g fitted (a hysteretic material under a non-uniform shear field)
// The named cause is the candidate with the lowest held-out error when it gains at least
// `min_gain_pct` on the physics mapping (input_scale: also on its own lambda = 1 variant);
// `none` when the measured gain lies within two sigmas of the prediction's tolerance band.
#include <string>
#include <vector>

#include "scpkit/mechanics/coil.hpp"
#include "scpkit/mechanics/material.hpp"

namespace scpkit {

struct PlyMappingData {
  std::vector<double> load_N;
  std::vector<double> thread_strain;  ///< fraction
  std::vector<double> scp_strain;     ///< fraction
  int plies = 2;
  double length_m = 0.1;
  CoilGeometry coil;  ///< the SCP's, as the file or the user states it
};

struct MappingCandidate {
  std::string cause;             ///< physics, spring_index, legs, active_coils, input_scale
  std::string model;             ///< the mapping in words
  double gain = 0.0;             ///< the gain it implies (fitted ones: on all readings)
  double heldout_rms_pct = 0.0;  ///< % of the SCP strain range
  double heldout_max_pct = 0.0;
  double gain_pct = 0.0;  ///< 100 (1 - heldout / physics heldout)
  bool supported = false;
  std::string evidence;
};

struct PlyMappingDiagnosis {
  Uncertain predicted_gain;
  double measured_gain = 0.0;
  double measured_r2 = 0.0;
  double miss_pct = 0.0;  ///< 100 (measured / predicted - 1)
  int folds = 0;
  std::vector<MappingCandidate> candidates;  ///< physics first
  std::string cause = "none";
};

struct PlyMappingOptions {
  int folds = 5;
  double min_gain_pct = 5.0;
  CoilTolerances tolerances;
};

/// IdentificationError when the data cannot be diagnosed (too few readings or cycles).
PlyMappingDiagnosis diagnose_ply_mapping(const PlyMappingData& data, const Material& material,
                                         const PlyMappingOptions& options = {});

}  // namespace scpkit
