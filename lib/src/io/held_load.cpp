#include "scpkit/io/held_load.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "scpkit/error.hpp"

namespace scpkit {

std::vector<std::size_t> load_runs(const Measurement& m) {
  const MeasurementColumn* column = m.find(Quantity::kLoad);
  if (!column || column->values.empty()) return {};
  const std::vector<double>& load = column->values;
  const MeasurementColumn* segment = m.find(Quantity::kSegment);
  const auto [lo, hi] = std::minmax_element(load.begin(), load.end());
  // tol 0: each change; else a reading farther than tol from its run's mean so far.
  const auto runs = [&](double tol) {
    std::vector<std::size_t> starts{0};
    double sum = load[0];
    for (std::size_t t = 1; t < load.size(); ++t) {
      const double mean = sum / static_cast<double>(t - starts.back());
      const bool moved = tol > 0.0 ? std::abs(load[t] - mean) > tol : load[t] != load[t - 1];
      if (moved || (segment && segment->values[t] != segment->values[t - 1])) {
        starts.push_back(t);
        sum = 0.0;
      }
      sum += load[t];
    }
    return starts;
  };
  std::vector<std::size_t> exact = runs(0.0);
  if (load.size() >= kReadingsPerHeldLoad * exact.size()) return exact;
  return runs(kHeldLoadTolerance * (*hi - *lo));
}

bool load_is_held(const Measurement& m) {
  const MeasurementColumn* load = m.find(Quantity::kLoad);
  return column_varies(load) && load->values.size() >= kReadingsPerHeldLoad * load_runs(m).size();
}

std::vector<double> held_load_N(const Measurement& m) {
  const MeasurementColumn* load = m.find(Quantity::kLoad);
  if (!load)
    throw InputError(m.source(), m.header_line(), 0,
                     "the file needs a load column (load_g, load_mN or load_N)");
  std::vector<double> held = load->values;
  std::vector<std::size_t> starts = load_runs(m);
  starts.push_back(held.size());
  for (std::size_t k = 0; k + 1 < starts.size(); ++k) {
    const auto first = held.begin() + static_cast<std::ptrdiff_t>(starts[k]);
    const auto last = held.begin() + static_cast<std::ptrdiff_t>(starts[k + 1]);
    // A run held exactly keeps its value to the last bit (a mean of equal values may not).
    if (std::all_of(first, last, [&](double v) { return v == *first; })) continue;
    std::fill(first, last, std::accumulate(first, last, 0.0) / static_cast<double>(last - first));
  }
  return held;
}

}  // namespace scpkit
