#include "scpkit/mechanics/coil.hpp"

#include <fmt/format.h>

#include <cmath>

#include "scpkit/error.hpp"

namespace scpkit {
namespace {

double relative_variance(const CoilGeometry& g, const CoilTolerances& t) {
  const double rd = 4.0 * t.wire_d_m / g.wire_d_m;
  const double rD = 3.0 * t.mean_D_m / g.mean_D_m;
  return rd * rd + rD * rD + t.coils_rel * t.coils_rel;
}

}  // namespace

void CoilGeometry::validate() const {
  if (!(wire_d_m > 0.0) || !std::isfinite(wire_d_m))
    throw_invalid("wire diameter d must be > 0, got {} m", wire_d_m);
  if (!(mean_D_m > 0.0) || !std::isfinite(mean_D_m))
    throw_invalid("mean coil diameter D must be > 0, got {} m", mean_D_m);
  if (!(coils > 0.0) || !std::isfinite(coils))
    throw_invalid("number of coils n must be > 0, got {}", coils);
  if (legs != 1 && legs != 2) throw_invalid("legs must be 1 or 2, got {}", legs);
  if (!(length_m >= 0.0)) throw_invalid("length must be >= 0, got {} m", length_m);
  if (spring_index() < 1.0) {
    throw_invalid(
        "spring index D/d = {:.3g} < 1: no helix has a mean diameter below its wire diameter "
        "(is D the outer diameter? mean D = outer D - d)",
        spring_index());
  }
}

std::string CoilGeometry::caution() const {
  if (spring_index() < 3.0) {
    return fmt::format(
        "spring index {:.2f} < 3: the helical-spring formula neglects direct shear "
        "(factor 1 + 1/(2C^2) = {:.3f}) and curvature, which grow at small C",
        spring_index(), 1.0 + 0.5 / (spring_index() * spring_index()));
  }
  return "";
}

double spring_stiffness(double G, const CoilGeometry& g) {
  g.validate();
  if (!(G > 0.0)) throw_invalid("shear modulus must be > 0, got {} Pa", G);
  // n counts the coils of all legs: each leg has n / legs, and the legs act in parallel.
  const double per_leg = g.coils / g.legs;
  return g.legs * G * std::pow(g.wire_d_m, 4) / (8.0 * per_leg * std::pow(g.mean_D_m, 3));
}

Uncertain spring_stiffness(const Uncertain& G, const CoilGeometry& g, const CoilTolerances& t) {
  const double K = spring_stiffness(G.value, g);
  const double rG = G.relative();
  return {K, K * std::sqrt(rG * rG + relative_variance(g, t))};
}

Uncertain stiffness_ratio(const CoilGeometry& a, const CoilGeometry& b, const CoilTolerances& t) {
  const double r = spring_stiffness(1.0, a) / spring_stiffness(1.0, b);
  return {r, r * std::sqrt(relative_variance(a, t) + relative_variance(b, t))};
}

}  // namespace scpkit
