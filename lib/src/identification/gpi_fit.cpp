#include "scpkit/identification/gpi_fit.hpp"

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "scpkit/error.hpp"
#include "scpkit/identification/nnls.hpp"

namespace scpkit {
namespace {

// theta = (a_R, d_min, d_max) -> envelopes. A shift common to both envelopes moves every
// operator (and its initial state) by the same amount, which the free bias absorbs: it is
// not identifiable, so gamma_R(v_min) = 0 fixes it.
GpiModel shape_from(const double* theta, const GpiModel& base) {
  GpiModel m = base;
  m.right = {theta[0], -theta[0] * base.v_min};
  const double lmin = m.right(m.v_min) + theta[1], lmax = m.right(m.v_max) + theta[2];
  m.left.a = (lmax - lmin) / (m.v_max - m.v_min);
  m.left.b = lmin - m.left.a * m.v_min;
  return m;
}

struct Projected {
  std::vector<double> weights;
  double bias = 0.0;
  std::vector<double> residuals;
};

// For fixed envelopes: exact sign-constrained weights and free bias; residuals.
Projected project(const GpiModel& shape, std::span<const double> v, std::span<const double> y,
                  std::span<const char> starts, int sign) {
  const auto cols = gpi_operator_outputs(shape, v, starts);
  const auto m = static_cast<Eigen::Index>(cols.size());
  const auto n = static_cast<Eigen::Index>(v.size());
  Eigen::MatrixXd A(n, m + 1);
  for (Eigen::Index j = 0; j < m; ++j) {
    for (Eigen::Index t = 0; t < n; ++t) A(t, j) = sign * cols[j][t];
  }
  A.col(m).setOnes();
  const Eigen::Map<const Eigen::VectorXd> yv(y.data(), n);
  const Eigen::MatrixXd G = A.transpose() * A / static_cast<double>(n);
  const Eigen::VectorXd f = A.transpose() * yv / static_cast<double>(n);
  std::vector<bool> constrained(static_cast<std::size_t>(m + 1), true);
  constrained.back() = false;
  const NnlsResult r = solve_nnls(G, f, constrained);
  Projected p;
  for (Eigen::Index j = 0; j < m; ++j) p.weights.push_back(sign * r.x[j]);
  p.bias = r.x[m];
  const Eigen::VectorXd e = A * r.x - yv;
  p.residuals.assign(e.data(), e.data() + n);
  return p;
}

struct VarProCost {
  const GpiModel* base;
  std::span<const double> v, y;
  std::span<const char> starts;
  int sign;
  bool operator()(double const* const* params, double* residuals) const {
    const GpiModel shape = shape_from(params[0], *base);
    if (!(shape.right.a > 0.0) || !(shape.left.a > 0.0)) return false;
    const Projected p = project(shape, v, y, starts, sign);
    std::copy(p.residuals.begin(), p.residuals.end(), residuals);
    return true;
  }
};

}  // namespace

bool GpiFitOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (operators < 1 || operators > 100) return fail("operators must be 1..100");
  if (sign < -1 || sign > 1) return fail("sign must be -1, 0 or +1");
  if (max_iterations < 0) return fail("max_iterations must be >= 0");
  if (!std::isfinite(max_radius)) return fail("max_radius must be finite");
  return true;
}

std::vector<std::vector<double>> gpi_operator_outputs(const GpiModel& shape,
                                                      std::span<const double> input,
                                                      std::span<const char> starts) {
  const std::size_t n = input.size();
  std::vector<std::vector<double>> cols(shape.radii.size(), std::vector<double>(n));
  GpiState s;
  for (std::size_t t = 0; t < n; ++t) {
    if (t == 0 || (!starts.empty() && starts[t]))
      s = GpiState::at_lower_turning_point(shape, shape.v_min);
    const double v = std::clamp(input[t], shape.v_min, shape.v_max);
    const double gr = shape.right(v), gl = shape.left(v);
    for (std::size_t j = 0; j < shape.radii.size(); ++j) {
      s.w[j] = std::min(gl + shape.radii[j], std::max(gr - shape.radii[j], s.w[j]));
      cols[j][t] = s.w[j];
    }
    s.v = v;
  }
  return cols;
}

GpiFit fit_gpi(std::span<const double> input, std::span<const double> output,
               std::span<const char> starts, const GpiFitOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InvalidArgument("GPI fit options: " + why);
  const std::size_t n = input.size();
  if (output.size() != n || (!starts.empty() && starts.size() != n))
    throw_invalid("GPI fit: sizes differ");
  const std::size_t unknowns = static_cast<std::size_t>(options.operators) + 5;
  if (n < 2 * unknowns) {
    throw IdentificationError(
        fmt::format("{} samples are too few for a GPI model with {} operators (need >= {})", n,
                    options.operators, 2 * unknowns));
  }
  for (std::size_t t = 0; t < n; ++t) {
    if (!std::isfinite(input[t]) || !std::isfinite(output[t])) {
      throw IdentificationError(fmt::format("sample {} is not finite", t + 1));
    }
  }
  const auto [vmin, vmax] = std::minmax_element(input.begin(), input.end());
  const auto [ymin, ymax] = std::minmax_element(output.begin(), output.end());
  if (!(*vmax > *vmin)) throw IdentificationError("the input never changes: nothing to identify");
  if (!(*ymax > *ymin))
    throw IdentificationError("the response never changes: nothing to identify");
  const int sign = options.sign != 0 ? options.sign : response_direction(input, output);

  GpiModel base;
  base.v_min = *vmin;
  base.v_max = *vmax;
  const double range = base.v_max - base.v_min;
  const double rmax = options.max_radius >= 0.0 ? options.max_radius : 0.25 * range;
  const int N = options.operators;
  for (int j = 0; j < N; ++j) {
    base.radii.push_back(N == 1 ? 0.0 : rmax * j / (N - 1));
    base.weights.push_back(0.0);
  }
  // A few starts (slope, band width): the cost is not convex in the envelopes.
  double theta[3] = {1.0, 0.02 * range, 0.02 * range};
  ceres::Solver::Summary summary;
  double best_cost = std::numeric_limits<double>::infinity();
  for (const double a0 : {1.0, 3.0}) {
    for (const double d0 : {0.02, 0.3}) {
      double t[3] = {a0, d0 * range, d0 * range};
      auto* functor = new VarProCost{&base, input, output, starts, sign};
      auto* cost = new ceres::DynamicNumericDiffCostFunction<VarProCost, ceres::CENTRAL>(functor);
      cost->AddParameterBlock(3);
      cost->SetNumResiduals(static_cast<int>(n));
      ceres::Problem problem;
      problem.AddResidualBlock(cost, nullptr, t);
      problem.SetParameterLowerBound(t, 0, 1e-3);
      problem.SetParameterLowerBound(t, 1, 0.0);
      problem.SetParameterLowerBound(t, 2, 0.0);
      ceres::Solver::Options so;
      so.max_num_iterations = options.max_iterations;
      so.linear_solver_type = ceres::DENSE_QR;
      so.logging_type = ceres::SILENT;
      so.num_threads = 1;
      ceres::Solver::Summary s;
      ceres::Solve(so, &problem, &s);
      if (s.final_cost < best_cost) {
        best_cost = s.final_cost;
        std::copy(t, t + 3, theta);
        summary = s;
      }
    }
  }

  GpiFit fit;
  fit.model = shape_from(theta, base);
  const Projected p = project(fit.model, input, output, starts, sign);
  fit.model.weights = p.weights;
  fit.model.bias = p.bias;
  fit.model.validate();
  std::vector<double> predicted(n);
  for (std::size_t t = 0; t < n; ++t) predicted[t] = output[t] + p.residuals[t];
  fit.summary.train = error_metrics(output, predicted);
  fit.summary.converged = summary.termination_type == ceres::CONVERGENCE;
  fit.summary.iterations = static_cast<int>(summary.iterations.size());
  fit.summary.initial_cost = summary.initial_cost;
  fit.summary.final_cost = summary.final_cost;
  fit.summary.message = summary.message;
  return fit;
}

std::string GpiFitSummary::BriefReport() const {
  return fmt::format(
      "GPI fit: {} after {} Ceres iterations (cost {:.4g} -> {:.4g})\n"
      "  identification: E_max {:.3f} %, E_RMS {:.3f} % of the response range",
      converged ? "converged" : "stopped (" + message + ")", iterations, initial_cost, final_cost,
      train.max_pct_range, train.rms_pct_range);
}

}  // namespace scpkit
