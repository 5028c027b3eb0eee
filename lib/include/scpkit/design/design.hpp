#pragma once
// Design evaluation: what an SCP actuator of a given ply count and coil will do, predicted from
// one characterised thread (a paired thread/SCP test), before it is made.
//
//   thread, q plies:  Gamma_p[(p/q) F]                                (corrected Eq. 7)
//   SCP, q plies:     eps = g_q Gamma_p[(p/q) F] + c_p g_q / g_p,
//                     g_q = g_p (q/p) K_SCP,p / K_SCP,q                (corrected Eq. 8)
//   K = legs G d^4 / (8 n D^3), D the mean coil diameter
//
// Figures, on a major loop between the working loads (one warm-up cycle, then the measured
// cycle of `protocol_steps` readings), or on a given load protocol:
//   stroke        strain at the highest load minus strain at the lowest, on the rising branch
//                 (mm on the actuator's length, and % strain), with the band the coil
//                 tolerances imply;
//   hysteresis    the largest gap between the falling and the rising branch at equal load,
//                 % of the stroke.
// Voltage side (when a characterised voltage model is given): the thermal stroke at a working
// load and the voltage for a target stroke. Transfer assumption (docs/design.md): the thermal
// contraction is a material strain at the per-ply load, carried to the new coil by the same
// gain ratio as the load-side strain, and the drive scales with length (same heating per unit
// length): f2_q(F) = f2_ref((p_ref/q) F) g_q / g_ref, V_q = V_ref L_q / L_ref.
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "scpkit/hysteresis/augmented.hpp"
#include "scpkit/hysteresis/preisach.hpp"
#include "scpkit/mechanics/coil.hpp"
#include "scpkit/mechanics/material.hpp"
#include "scpkit/mechanics/ply_mapping.hpp"

namespace scpkit {

/// The characterised thread and actuator every design is predicted from.
struct ThreadCharacterisation {
  PreisachModel thread{PreisachGrid{}, Eigen::VectorXd::Zero(PreisachGrid{}.cells()), 0.0};
  int plies = 2;            ///< p
  GainFit scp_gain;         ///< g_p, c_p
  CoilGeometry coil;        ///< the characterised SCP's coil
  double load_min_N = 0.0;  ///< identified loads of the p-ply thread
  double load_max_N = 0.0;
  /// Optional voltage side of the characterised actuator (augmented model, strain response).
  std::optional<AugmentedModel> voltage;
  double voltage_length_mm = 0.0;  ///< that actuator's length
  int voltage_plies = 0;           ///< its ply count (default p)
};

struct DesignSpec {
  int plies = 2;
  CoilGeometry coil;        ///< d, D (mean), n, legs, length
  double load_min_N = 0.0;  ///< working loads
  double load_max_N = 0.0;
  int protocol_steps = 100;        ///< readings in the measured major-loop cycle
  std::vector<double> protocol_N;  ///< replaces the major loop when not empty
  double working_load_N = 0.0;     ///< voltage side: load for thermal stroke (0: none)
  double target_stroke_mm = 0.0;   ///< voltage side: stroke to reach (0: none)
  /// Strains beyond this (load side along the loop, or thermal) are outside what SCP
  /// actuators reach (8-21 % self-coiled, up to 49 % mandrel-coiled, PHYSICS.md section 5):
  /// the helical-spring mapping is then an extrapolation, and the design is infeasible.
  double max_strain_pct = 50.0;
  CoilTolerances tolerances;
};

struct DesignResult {
  bool feasible = true;
  std::string reason;  ///< the first failed check, "" when feasible
  double spring_index = 0.0;
  double pitch_mm = 0.0;
  Uncertain stiffness_N_per_m;
  Uncertain gain;
  double stroke_mm = 0.0, stroke_sigma_mm = 0.0, stroke_pct = 0.0;
  double hysteresis_pct = 0.0;         ///< -1 for a given protocol (defined on the major loop)
  double thermal_stroke_mm = -1.0;     ///< -1 when no voltage model
  double voltage_for_target_V = -1.0;  ///< -1 when not computed or unreachable
  bool voltage_extrapolated = false;
  std::vector<double>
      strain_pct;  ///< the predicted SCP strain along the protocol (filled on request)
};

/// Scratch memory for evaluate_design, one per thread: no allocation per design once warm.
struct DesignWorkspace {
  PreisachState state{PreisachState::negative_saturation(PreisachGrid{})};
  std::vector<double> loads, strain;
};

/// Evaluates one design. Never throws for an infeasible design (the reason says why); throws
/// InvalidArgument for an inconsistent characterisation.
DesignResult evaluate_design(const ThreadCharacterisation& ch, const Material& material,
                             const DesignSpec& spec, DesignWorkspace& ws, bool keep_curve = false);

/// The coil wire diameter of a q-ply thread: the card's reference geometry for q plies, else
/// the characterised coil's d scaled by sqrt(q / p) (cross-section proportional to plies).
double wire_diameter_for(const Material& material, const ThreadCharacterisation& ch, int plies);

}  // namespace scpkit
