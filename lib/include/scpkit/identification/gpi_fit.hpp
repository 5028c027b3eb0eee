#pragma once
// Identification of a GPI model (paper 000 Section III-A, with Ceres in place of fmincon).
//
// Variable projection: the weights and the bias enter linearly, so for given envelopes they
// are the exact sign-constrained least-squares answer (solve_nnls, one sign for every weight:
// every partial sum keeps that sign, so the model stays invertible); Ceres minimises the
// remaining residual over three envelope parameters, parametrised so that order
// preservation holds by construction:
//   gamma_R(v) = a_R (v - v_min),  a_R > 0   (a shift common to both envelopes is absorbed
//                                              by the bias c, so b_R is fixed)
//   gamma_L(v_min) = gamma_R(v_min) + d_min,  gamma_L(v_max) = gamma_R(v_max) + d_max,
//   d_min, d_max >= 0  (so gamma_R <= gamma_L on the whole range).
// Radii are fixed, r_j = j / (N) * max_radius (paper 000: 11 operators, r_j = j / 10).
#include <span>
#include <string>

#include "scpkit/hysteresis/gpi.hpp"
#include "scpkit/metrics.hpp"

namespace scpkit {

struct GpiFitOptions {
  int operators = 11;        ///< N + 1
  double max_radius = -1.0;  ///< largest radius; < 0: a quarter of the input range
  int sign = 0;              ///< +1 / -1 weights; 0: from the data
  int max_iterations = 200;  ///< Ceres iterations
  bool IsValid(std::string* why) const;
};

struct GpiFitSummary {
  bool converged = false;
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  ErrorMetrics train;
  std::string message;
  std::string BriefReport() const;
};

struct GpiFit {
  GpiModel model;
  GpiFitSummary summary;
};

/// `segment_starts` (optional, one flag per sample): the memory restarts at the lower turning
/// point where a flag is set (each constant-load segment from the virgin state).
/// IdentificationError when the data cannot identify the model.
GpiFit fit_gpi(std::span<const double> input, std::span<const double> output,
               std::span<const char> segment_starts, const GpiFitOptions& options);

/// The GPI operators' outputs for a given model shape (weights ignored), one column each,
/// restarting at segment starts. Used by the fit and by tests.
std::vector<std::vector<double>> gpi_operator_outputs(const GpiModel& shape,
                                                      std::span<const double> input,
                                                      std::span<const char> segment_starts);

}  // namespace scpkit
