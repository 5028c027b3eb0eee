#include "scpkit/identification/nnls.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "scpkit/error.hpp"

namespace scpkit {
namespace {

double tolerance_scale(const Eigen::MatrixXd& G, const Eigen::VectorXd& f) {
  const double fmax = f.size() ? f.cwiseAbs().maxCoeff() : 0.0;
  const double gmax = G.size() ? G.diagonal().cwiseAbs().maxCoeff() : 0.0;
  return std::max({fmax, gmax, 1e-300});
}

// Solves G_PP z_P = f_P; z is zero outside P. Returns the number of tiny pivots.
int solve_passive(const Eigen::MatrixXd& G, const Eigen::VectorXd& f, const std::vector<int>& P,
                  Eigen::VectorXd& z) {
  const auto p = static_cast<Eigen::Index>(P.size());
  z.setZero();
  if (p == 0) return 0;
  Eigen::MatrixXd Gp(p, p);
  Eigen::VectorXd fp(p);
  for (Eigen::Index a = 0; a < p; ++a) {
    fp[a] = f[P[a]];
    for (Eigen::Index b = 0; b < p; ++b) Gp(a, b) = G(P[a], P[b]);
  }
  Eigen::LDLT<Eigen::MatrixXd> ldlt(Gp);
  const Eigen::VectorXd d = ldlt.vectorD().cwiseAbs();
  const double dmax = d.maxCoeff();
  int tiny = 0;
  for (Eigen::Index a = 0; a < p; ++a) tiny += d[a] <= 1e-13 * dmax ? 1 : 0;
  Eigen::VectorXd zp = ldlt.solve(fp);
  if (!zp.allFinite()) {
    // Singular block: fall back to a minimum-norm-like solution through a small ridge.
    Gp.diagonal().array() += 1e-12 * dmax;
    zp = Gp.ldlt().solve(fp);
  }
  for (Eigen::Index a = 0; a < p; ++a) z[P[a]] = zp[a];
  return tiny;
}

// Lawson-Hanson active-set iteration from a feasible x. Updates x, the passive flags and r.
void lawson_hanson(const Eigen::MatrixXd& G, const Eigen::VectorXd& f,
                   const std::vector<bool>& constrained, double tol, int max_iter,
                   Eigen::VectorXd& x, std::vector<char>& in_p, NnlsResult& r) {
  const Eigen::Index n = f.size();
  for (Eigen::Index i = 0; i < n; ++i) {
    if (constrained[i] && !(x[i] > 0.0)) x[i] = 0.0;
    in_p[i] = !constrained[i] || x[i] > 0.0;
  }
  auto passive = [&] {
    std::vector<int> P;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (in_p[i]) P.push_back(static_cast<int>(i));
    }
    return P;
  };
  Eigen::VectorXd z(n);
  bool need_inner = true;
  for (int it = 0; it < max_iter; ++it, ++r.iterations) {
    if (!need_inner) {
      const Eigen::VectorXd w = f - G * x;
      Eigen::Index t = -1;
      double best = tol;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (!in_p[i] && w[i] > best) {
          best = w[i];
          t = i;
        }
      }
      if (t < 0) {
        r.converged = true;
        return;
      }
      in_p[t] = 1;
    }
    need_inner = false;
    for (Eigen::Index inner = 0; inner <= n; ++inner) {
      r.rank_deficient_pivots = solve_passive(G, f, passive(), z);
      double alpha = 1.0;
      bool feasible = true;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (in_p[i] && constrained[i] && z[i] <= 0.0) {
          feasible = false;
          const double denom = x[i] - z[i];
          if (denom > 0.0) alpha = std::min(alpha, x[i] / denom);
        }
      }
      if (feasible) {
        x = z;
        break;
      }
      x += alpha * (z - x);
      for (Eigen::Index i = 0; i < n; ++i) {
        if (in_p[i] && constrained[i] && x[i] <= tol * 1e-3 / std::max(G(i, i), 1e-300)) {
          in_p[i] = 0;
          x[i] = 0.0;
        }
      }
    }
  }
}

}  // namespace

double kkt_violation(const Eigen::MatrixXd& G, const Eigen::VectorXd& f, const Eigen::VectorXd& x,
                     const std::vector<bool>& constrained, double relative_tolerance) {
  const double tol = relative_tolerance * tolerance_scale(G, f);
  const Eigen::VectorXd w = f - G * x;
  double worst = 0.0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    if (!constrained[i]) {
      worst = std::max(worst, std::abs(w[i]) / tol);
    } else {
      worst = std::max(worst, std::max(0.0, -x[i]) / (tol / std::max(G(i, i), 1e-300)));
      if (x[i] > 0.0) {
        worst = std::max(worst, std::abs(w[i]) / tol);  // interior: gradient vanishes
      } else {
        worst = std::max(worst, std::max(0.0, w[i]) / tol);  // at bound: gradient points out
      }
    }
  }
  return worst;
}

NnlsResult solve_nnls(const Eigen::MatrixXd& G, const Eigen::VectorXd& f,
                      const std::vector<bool>& constrained, const NnlsOptions& options,
                      const Eigen::VectorXd& warm_start) {
  const Eigen::Index n = f.size();
  if (G.rows() != n || G.cols() != n || static_cast<Eigen::Index>(constrained.size()) != n) {
    throw_invalid("NNLS: G is {}x{}, f has {}, mask has {}", G.rows(), G.cols(), n,
                  constrained.size());
  }
  if (!G.allFinite() || !f.allFinite()) throw_invalid("NNLS: non-finite Gram matrix or vector");
  const double tol = options.relative_tolerance * tolerance_scale(G, f);
  NnlsResult r;
  r.x = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd& x = r.x;

  // Phase 1: projected coordinate descent, keeping g = G x up to date (or a given start).
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  if (warm_start.size() == n) {
    for (Eigen::Index i = 0; i < n; ++i)
      x[i] = constrained[i] ? std::max(warm_start[i], 0.0) : warm_start[i];
  }
  const int sweeps = warm_start.size() == n ? 0 : options.warm_start_sweeps;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    double change = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double gii = G(i, i);
      if (!(gii > 0.0)) continue;
      double xi = x[i] + (f[i] - g[i]) / gii;
      if (constrained[i]) xi = std::max(xi, 0.0);
      const double dx = xi - x[i];
      if (dx != 0.0) {
        g += dx * G.col(i);
        x[i] = xi;
        change = std::max(change, std::abs(dx) * gii);
      }
    }
    if (change <= tol) break;
  }

  // Phase 2: block principal pivoting (Kim & Park, SIAM J. Sci. Comput. 33(6), 2011) from the
  // warm start's support: exchange every infeasible index at once, with Murty's single-index
  // backup rule to guarantee termination. Each step is one solve on the passive set.
  std::vector<char> in_p(static_cast<std::size_t>(n), 0);
  for (Eigen::Index i = 0; i < n; ++i) in_p[i] = !constrained[i] || x[i] > 0.0;
  auto passive = [&] {
    std::vector<int> P;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (in_p[i]) P.push_back(static_cast<int>(i));
    }
    return P;
  };
  const int max_iter =
      options.max_iterations > 0 ? options.max_iterations : static_cast<int>(3 * n + 30);
  Eigen::VectorXd z(n);
  int best_count = static_cast<int>(n) + 1, chances = 3;
  for (r.iterations = 0; r.iterations < max_iter; ++r.iterations) {
    r.rank_deficient_pivots = solve_passive(G, f, passive(), z);
    const Eigen::VectorXd grad = G * z - f;  // >= 0 required on the active set
    std::vector<Eigen::Index> bad;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!constrained[i]) continue;
      const double gtol = tol;
      if (in_p[i] ? z[i] < 0.0 : grad[i] < -gtol) bad.push_back(i);
    }
    if (bad.empty()) {
      x = z;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (constrained[i] && !in_p[i]) x[i] = 0.0;
      }
      r.converged = true;
      break;
    }
    const int count = static_cast<int>(bad.size());
    if (count < best_count) {
      best_count = count;
      chances = 3;
      for (Eigen::Index i : bad) in_p[i] = !in_p[i];
    } else if (chances > 0) {
      --chances;
      for (Eigen::Index i : bad) in_p[i] = !in_p[i];
    } else {
      in_p[bad.back()] = !in_p[bad.back()];  // backup rule: the largest infeasible index
    }
  }
  if (!r.converged) {
    // Safety net: Lawson-Hanson from the coordinate-descent point (always feasible).
    lawson_hanson(G, f, constrained, tol, max_iter, x, in_p, r);
  }
  r.kkt_violation = kkt_violation(G, f, x, constrained, options.relative_tolerance);
  r.passive = static_cast<int>(std::count(in_p.begin(), in_p.end(), 1));
  if (!r.converged) {
    r.message = fmt::format("NNLS stopped after {} iterations (KKT violation {:.3g})", r.iterations,
                            r.kkt_violation);
  } else {
    r.message = fmt::format("NNLS converged in {} active-set iterations, {} of {} entries free",
                            r.iterations, r.passive, n);
  }
  return r;
}

int response_direction(std::span<const double> input, std::span<const double> output) {
  const std::size_t n = std::min(input.size(), output.size());
  if (n == 0) return 1;
  double um = 0.0, ym = 0.0;
  for (std::size_t t = 0; t < n; ++t) {
    um += input[t];
    ym += output[t];
  }
  um /= static_cast<double>(n);
  ym /= static_cast<double>(n);
  double cov = 0.0;
  for (std::size_t t = 0; t < n; ++t) cov += (input[t] - um) * (output[t] - ym);
  return cov >= 0.0 ? 1 : -1;
}

}  // namespace scpkit
