#pragma once
// The virtual test rig: a ground-truth thread material, a ply count, a coil, a load protocol,
// a sensor and chosen non-ideal effects, producing a measurement file in the SPEC format with
// the truth in its metadata. Used by the examples, the tests, and users planning experiments.
//
// Ground truth (docs/rig.md):
//   thread, q plies:  eps_thr,q[F] = Gamma*[F / q]        (Gamma* a fine Preisach operator
//                                                          over the per-ply load, slope 1/(E A))
//   SCP:              eps_SCP,q = g_q eps_thr,q + c,  g_q = K_thr,q / K_SCP,q
//                     K_thr,q = E q A / l,  K_SCP,q = legs G d^4 / (8 n D^3)
//   sensor:           displacement + N(0, noise_mm), quantised to resolution_mm
// Effects, each with a magnitude (0 = off), applied before the sensor:
//   creep                     fraction of the strain that is viscoelastic (Kelvin element,
//                             time constant creep_tau_s, relaxing during each dwell)
//   drift                     linear trend over the test, as a fraction of the strain range
//   lonely_stroke             running-maximum offset, fraction of the range (training)
//   outliers                  spike size in strain ranges, on ~1 % of readings
//   minor_loop_noncongruence  a of the output-dependent loop height y + a R z^2,
//                             z = max(0, (y - y_0) / R) (y_0 the first reading, R the nominal
//                             strain range; a <= 1)
//   load_shape_coupling       (voltage) h = (1 - w(F)) H[v] + w(F) H2[v], w = m (F - F_lo) / dF,
//                             H2 a differently shaped operator normalised like H
//   offset_nonlinearity       (voltage) knee k(F) = exp(-(F - F_lo) / (0.2 dF)) at low load:
//                             f1 += m R k(F), f2 *= 1 - m k(F)  (R: the largest |f2|)
// Voltage tests (test = "voltage"): y = f2(F) H[v] + f1(F) per constant-load segment, each from
// H's initial state; lonely_stroke there is re-armed at every load change (paper 001).
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "scpkit/hysteresis/augmented.hpp"
#include "scpkit/hysteresis/preisach.hpp"
#include "scpkit/mechanics/coil.hpp"
#include "scpkit/mechanics/material.hpp"

namespace scpkit {

struct LoadProtocol {
  double min_g = 20.0;           ///< lowest load for a 2-ply thread
  double max_g = 250.0;          ///< highest load for a 2-ply thread
  bool scale_with_plies = true;  ///< loads times plies / 2 (paper 002: 20-250, 40-500, 60-750 g)
  /// damped: an oscillation whose amplitude falls to 15 % over the cycles (paper 002);
  /// repeated: full cycles min -> max -> min of constant amplitude (paper 001's training cycles).
  std::string shape = "damped";
  int cycles = 8;          ///< oscillation cycles
  int steps_per_half = 8;  ///< readings per half cycle
  int minor_loops = 3;     ///< random minor loops, each run twice, after the damped part
  /// Each minor loop a <-> b is also run after a different history (from the minimum load, so
  /// b is first reached from below instead of after the maximum): loops between the same
  /// extrema from different histories, the only place congruency can be tested.
  bool congruency = false;
  /// Readings per hold: 1 reads once at the end of each hold; k > 1 reads k times, equally
  /// spaced in time, during each hold (what shows a response still moving).
  int readings_per_hold = 1;
  double dwell_s = 180.0;  ///< hold before each reading (paper 002: 3 min)
  /// 0: every hold lasts dwell_s. s > 0: each hold drawn log-uniformly in
  /// [dwell_s / (1 + s), dwell_s (1 + s)] (protocols that vary the dwell expose creep).
  double dwell_spread = 0.0;
};

/// Voltage tests at several constant loads (paper 000: 8 loads 294-980 mN, damped voltage
/// oscillation 0-5.1 V, 60 s dwell; paper 001: load switched 400 g -> 200 g).
struct VoltageProtocol {
  /// 294 ... 980 mN, tested in this order (any order: a drift is separable from the load only
  /// when the order is not monotone).
  std::vector<double> loads_g = {30, 40, 50, 60, 70, 80, 90, 100};
  double v_max = 5.1;
  /// damped: an oscillation narrowing towards mid-range (paper 000), back to 0 V at the end;
  /// repeated: full cycles 0 -> v_max -> 0 V (paper 001's training cycles at one load).
  std::string shape = "damped";
  int cycles = 2;          ///< cycles per load
  int steps_per_half = 9;  ///< readings per half cycle
  double dwell_s = 60.0;
  double dwell_spread = 0.0;  ///< as LoadProtocol::dwell_spread
  int readings_per_hold = 1;  ///< as LoadProtocol::readings_per_hold
  std::string truth =
      "gpi";  ///< H of the truth: gpi (paper 000's identified envelopes) or preisach
};

struct RigEffects {
  double creep = 0.0;
  double creep_tau_s = 60.0;
  double drift = 0.0;
  double lonely_stroke = 0.0;
  /// Voltage tests: the lonely stroke's sign after a load increase, relative to the first load
  /// and to decreases: -1 (paper 001's open case: the repeatable loop lies on the other side)
  /// or +1 (one sign throughout).
  double lonely_sign_after_increase = -1.0;
  double outliers = 0.0;
  double minor_loop_noncongruence = 0.0;
  double load_shape_coupling = 0.0;  ///< voltage tests: normalised loop shape changes with load
  double offset_nonlinearity = 0.0;  ///< voltage tests: knee in f1, f2 at low load
};

struct RigSpec {
  std::uint64_t seed = 1;
  std::string test = "load";  ///< load (load -> strain) or voltage (voltage -> strain under loads)
  VoltageProtocol voltage;    ///< used when test = "voltage"
  std::string specimen = "pair";  ///< thread, scp, or pair (both strains in one file)
  int plies = 2;
  std::string material = "nylon-110-34-dtex";
  double length_mm = 100.0;
  std::optional<CoilGeometry> coil;  ///< default: the material card's geometry for `plies`
  double scp_offset_pct = 0.2;       ///< c in eps_SCP = g eps_thr + c, strain-%
  LoadProtocol protocol;
  double resolution_mm = 0.04;
  double noise_mm = 0.01;
  RigEffects effects;
  std::optional<std::vector<double>> load_sequence_g;  ///< replaces the protocol when given

  void validate() const;  ///< InvalidArgument with the reason
};

/// Reads a rig description (TOML). InputError naming file, line and column.
RigSpec load_rig_spec(const std::filesystem::path& path);

struct RigRun {
  std::map<std::string, std::string> metadata;  ///< SPEC metadata plus truth_* keys
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  double true_gain = 0.0;  ///< g_q of the truth
  std::string to_csv() const;
};

/// The rig's ground-truth thread operator over the per-ply load in N (strain as fraction).
PreisachModel rig_thread_truth(const Material& material);

/// Runs the rig. Deterministic for a given spec (seeded).
RigRun run_rig(const RigSpec& spec, const Material& material);

/// The load protocol alone, in grams (damped oscillation then minor loops).
std::vector<double> rig_load_protocol(const RigSpec& spec);

/// The voltage side's ground truth: H normalised to H[0] = 0, H[v_max] = -1 on the first
/// rise, and the offset and range maps of paper 000 Eqs. 14-15 read as strain of a 70 mm
/// actuator: f1(F) = -(D(F) - D(294 mN)) / 70 mm, f2(F) = -P(F) / 70 mm, F in N.
struct VoltageTruth {
  HysteresisOperator h;
  Quadratic f1, f2;
};
VoltageTruth rig_voltage_truth(const RigSpec& spec);

}  // namespace scpkit
