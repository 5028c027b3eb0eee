#pragma once
// Private to the rig: what happens between the specimen's strain and the file. Drift and
// outliers (effects that belong to the measurement, scaled by the channel's range), then the
// displacement sensor: Gaussian noise and quantisation to its resolution.
#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "scpkit/rig/rig.hpp"

namespace scpkit::detail {

/// Hold durations: constant, or log-uniform in [dwell / (1 + spread), dwell (1 + spread)] from
/// a stream of their own (so a spread of 0 leaves every other draw of the rig unchanged).
inline std::vector<double> dwell_times(std::size_t n, double dwell, double spread,
                                       std::uint64_t seed) {
  std::vector<double> d(n, dwell);
  if (spread > 0.0) {
    std::mt19937_64 rng(seed * 6364136223846793005ULL + 1442695040888963407ULL);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (double& x : d) x = dwell * std::exp(U(rng) * std::log1p(spread));
  }
  return d;
}

/// The readings of a protocol whose step k is held for dwell[k]: `per_hold` readings per hold,
/// equally spaced in time. For reading i: its step, the time since the previous reading, and
/// how long its input has been held when it is taken (the dwell_s column).
struct Readings {
  std::vector<std::size_t> step;
  std::vector<double> dt, held;
};
inline Readings readings_during_holds(const std::vector<double>& dwell, int per_hold) {
  Readings r;
  for (std::size_t k = 0; k < dwell.size(); ++k) {
    for (int j = 1; j <= per_hold; ++j) {
      r.step.push_back(k);
      r.dt.push_back(dwell[k] / per_hold);
      r.held.push_back(dwell[k] * j / per_hold);
    }
  }
  return r;
}

/// The truth_effects metadata line.
inline std::string effects_text(const RigEffects& e) {
  return fmt::format(
      "creep={:g} creep_tau_s={:g} drift={:g} lonely_stroke={:g} outliers={:g} "
      "minor_loop_noncongruence={:g} load_shape_coupling={:g} offset_nonlinearity={:g}",
      e.creep, e.creep_tau_s, e.drift, e.lonely_stroke, e.outliers, e.minor_loop_noncongruence,
      e.load_shape_coupling, e.offset_nonlinearity);
}

/// Strain-% readings of one channel. `range` is the channel's nominal strain range (fraction).
inline std::vector<double> measure_channel(const std::vector<double>& strain,
                                           const std::vector<double>& time_s, double range,
                                           const RigSpec& spec, std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const RigEffects& e = spec.effects;
  const double t_end = time_s.empty() ? 1.0 : time_s.back();
  std::vector<double> pct(strain.size());
  int spikes = 0;
  for (std::size_t k = 0; k < strain.size(); ++k) {
    double s = strain[k] + e.drift * range * time_s[k] / t_end;
    if (e.outliers > 0.0 && U(rng) < 0.01) {
      s += (U(rng) < 0.5 ? -1.0 : 1.0) * e.outliers * range * (1.0 + U(rng));
      ++spikes;
    }
    double disp = s * spec.length_mm + spec.noise_mm * normal(rng);
    if (spec.resolution_mm > 0.0) disp = std::round(disp / spec.resolution_mm) * spec.resolution_mm;
    pct[k] = 100.0 * disp / spec.length_mm;
  }
  // A record asked to hold outliers holds at least one (about 1 % of a short record may be
  // none): then one reading in its middle half gets the spike.
  if (e.outliers > 0.0 && spikes == 0 && strain.size() >= 4) {
    const double n = static_cast<double>(strain.size());
    const auto k = static_cast<std::size_t>(n / 4.0 + U(rng) * n / 2.0);
    double disp = pct[k] * spec.length_mm / 100.0 + (U(rng) < 0.5 ? -1.0 : 1.0) * e.outliers *
                                                        range * (1.0 + U(rng)) * spec.length_mm;
    if (spec.resolution_mm > 0.0) disp = std::round(disp / spec.resolution_mm) * spec.resolution_mm;
    pct[k] = 100.0 * disp / spec.length_mm;
  }
  return pct;
}

}  // namespace scpkit::detail
