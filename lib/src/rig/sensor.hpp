#pragma once
// Private to the rig: what happens between the specimen's strain and the file. Drift and
// outliers (effects that belong to the measurement, scaled by the channel's range), then the
// displacement sensor: Gaussian noise and quantisation to its resolution.
#include <cmath>
#include <random>
#include <vector>

#include "scpkit/rig/rig.hpp"

namespace scpkit::detail {

/// Strain-% readings of one channel. `range` is the channel's nominal strain range (fraction).
inline std::vector<double> measure_channel(const std::vector<double>& strain,
                                           const std::vector<double>& time_s, double range,
                                           const RigSpec& spec, std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const RigEffects& e = spec.effects;
  const double t_end = time_s.empty() ? 1.0 : time_s.back();
  std::vector<double> pct(strain.size());
  for (std::size_t k = 0; k < strain.size(); ++k) {
    double s = strain[k] + e.drift * range * time_s[k] / t_end;
    if (e.outliers > 0.0 && U(rng) < 0.01) {
      s += (U(rng) < 0.5 ? -1.0 : 1.0) * e.outliers * range * (1.0 + U(rng));
    }
    double disp = s * spec.length_mm + spec.noise_mm * normal(rng);
    if (spec.resolution_mm > 0.0) disp = std::round(disp / spec.resolution_mm) * spec.resolution_mm;
    pct[k] = 100.0 * disp / spec.length_mm;
  }
  return pct;
}

}  // namespace scpkit::detail
