#include "scpkit/hysteresis/augmented.hpp"

#include <cmath>

#include "scpkit/error.hpp"

namespace scpkit {

bool Quadratic::crosses_zero(double lo, double hi) const {
  const double a = (*this)(lo), b = (*this)(hi);
  if (a == 0.0 || b == 0.0 || (a < 0.0) != (b < 0.0)) return true;
  if (c2 != 0.0) {  // an extremum inside may dip through zero
    const double x = -c1 / (2.0 * c2);
    if (x > lo && x < hi) {
      const double m = (*this)(x);
      if (m == 0.0 || (m < 0.0) != (a < 0.0)) return true;
    }
  }
  return false;
}

void AugmentedModel::validate() const {
  if (!(load_min <= load_max)) throw_invalid("augmented model: empty load range");
  if (f2.crosses_zero(load_min, load_max)) {
    throw_invalid(
        "augmented model: the range map f2 crosses zero inside the identified loads [{}, {}] N; "
        "the model cannot be normalised or inverted there",
        load_min, load_max);
  }
}

bool AugmentedModel::outside_load_range(double F) const {
  const double tol = 1e-9 * (std::abs(load_max) + 1.0);
  return F < load_min - tol || F > load_max + tol;
}

std::vector<double> AugmentedModel::simulate(std::span<const double> load,
                                             std::span<const double> input,
                                             std::span<const char> starts) const {
  if (load.size() != input.size())
    throw_invalid("augmented model: {} loads vs {} inputs", load.size(), input.size());
  std::vector<double> y = h.simulate(input, starts);
  for (std::size_t t = 0; t < y.size(); ++t) y[t] = f2(load[t]) * y[t] + f1(load[t]);
  return y;
}

std::vector<InverseStep> AugmentedModel::invert(std::span<const double> load,
                                                std::span<const double> target,
                                                std::span<const char> starts) const {
  if (load.size() != target.size())
    throw_invalid("augmented model: {} loads vs {} targets", load.size(), target.size());
  std::vector<double> hd(target.size());
  for (std::size_t t = 0; t < hd.size(); ++t) {
    const double g = f2(load[t]);
    if (g == 0.0) throw_invalid("augmented model: f2 is zero at load {} N", load[t]);
    hd[t] = (target[t] - f1(load[t])) / g;
  }
  std::vector<InverseStep> steps = h.invert(hd, starts);
  for (std::size_t t = 0; t < steps.size(); ++t)
    steps[t].output = f2(load[t]) * steps[t].output + f1(load[t]);
  return steps;
}

}  // namespace scpkit
