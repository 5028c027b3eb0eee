#include "scpkit/mechanics/ply_mapping.hpp"

#include <fmt/format.h>

#include <cmath>

#include "scpkit/error.hpp"

namespace scpkit {
namespace {

void check_plies(int p, int q) {
  if (p < 1 || q < 1) throw_invalid("ply counts must be >= 1, got p = {}, q = {}", p, q);
}

}  // namespace

PreisachModel map_thread_plies(const PreisachModel& thread_p, int p, int q) {
  check_plies(p, q);
  return thread_p.with_input_scale(static_cast<double>(p) / q);
}

PreisachModel paper_eq7_as_printed(const PreisachModel& thread_p, int p, int q) {
  check_plies(p, q);
  return thread_p.with_output_affine(static_cast<double>(p) / q, 0.0);
}

GainFit fit_scp_gain(std::span<const double> x, std::span<const double> y) {
  if (x.size() != y.size())
    throw_invalid("gain fit: {} thread vs {} SCP strains", x.size(), y.size());
  const std::size_t n = x.size();
  if (n < 3)
    throw IdentificationError(
        fmt::format("{} paired strains are too few for a gain (need >= 3)", n));
  double mx = 0.0, my = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= static_cast<double>(n);
  my /= static_cast<double>(n);
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
    syy += (y[i] - my) * (y[i] - my);
  }
  if (!(sxx > 0.0)) throw IdentificationError("thread strain never changes: no gain to fit");
  GainFit g;
  g.gain = sxy / sxx;
  g.offset = my - g.gain * mx;
  g.r2 = syy > 0.0 ? sxy * sxy / (sxx * syy) : 1.0;
  g.samples = static_cast<int>(n);
  return g;
}

Uncertain predict_scp_gain(double g_p, int p, const CoilGeometry& scp_p, int q,
                           const CoilGeometry& scp_q, const CoilTolerances& tol) {
  check_plies(p, q);
  const Uncertain ratio = stiffness_ratio(scp_p, scp_q, tol);  // K_SCP,p / K_SCP,q
  const double scale = g_p * q / p;
  return {scale * ratio.value, std::abs(scale) * ratio.sigma};
}

double paper_eq8_as_printed_gain(double g_p, int p, const CoilGeometry& scp_p, int q,
                                 const CoilGeometry& scp_q) {
  check_plies(p, q);
  return g_p * q / p * spring_stiffness(1.0, scp_q) / spring_stiffness(1.0, scp_p);
}

PreisachModel map_thread_to_scp(const PreisachModel& thread_p, int p, const GainFit& gain_p, int q,
                                double gain_q) {
  if (gain_p.gain == 0.0) throw_invalid("the p-ply SCP gain is zero");
  return map_thread_plies(thread_p, p, q)
      .with_output_affine(gain_q, gain_p.offset * gain_q / gain_p.gain);
}

}  // namespace scpkit
