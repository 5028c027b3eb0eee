#include "scpkit/hysteresis/preisach.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "scpkit/error.hpp"

namespace scpkit {

void PreisachGrid::validate() const {
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi)) {
    throw_invalid("Preisach grid needs finite lo < hi, got [{}, {}]", lo, hi);
  }
  if (levels < 1 || levels > 400) throw_invalid("Preisach levels must be 1..400, got {}", levels);
}

// ---------------------------------------------------------------- state

PreisachState::PreisachState(double lo, double hi) : lo_(lo), hi_(hi) {
  points_.reserve(64);
  prefix_.reserve(64);
  points_.push_back(lo);
}

PreisachState PreisachState::negative_saturation(const PreisachGrid& grid) {
  grid.validate();
  return PreisachState(grid.lo, grid.hi);
}

PreisachState PreisachState::after_cycle(const PreisachGrid& grid, double lo, double hi) {
  PreisachState s = negative_saturation(grid);
  if (!(lo < hi)) throw_invalid("PreisachState::after_cycle: needs lo < hi");
  s.apply(hi);
  s.apply(lo);
  return s;
}

PreisachState PreisachState::positive_saturation(const PreisachGrid& grid) {
  PreisachState s = negative_saturation(grid);
  s.points_.push_back(grid.hi);
  return s;
}

PreisachState PreisachState::from_turning_points(const PreisachGrid& grid,
                                                 std::vector<double> points) {
  PreisachState s = negative_saturation(grid);
  if (points.empty() || points.front() != grid.lo) {
    throw_invalid("a Preisach memory starts at lo = {}", grid.lo);
  }
  for (std::size_t i = 1; i < points.size(); ++i) {
    const double p = points[i];
    if (!(p >= grid.lo && p <= grid.hi)) throw_invalid("turning point {} outside the grid", p);
    const bool is_max = i % 2 == 1;
    if (is_max ? !(p > points[i - 1]) : !(p < points[i - 1])) {
      throw_invalid("turning points must alternate: entry {} ({}) does not", i, p);
    }
    // Dominance: every frozen extremum is beyond the next one of its kind.
    if (i >= 3 && i + 1 < points.size()) {
      if (is_max ? !(p < points[i - 2]) : !(p > points[i - 2])) {
        throw_invalid("turning point {} ({}) is wiped out by an earlier one", i, p);
      }
    }
  }
  s.points_ = std::move(points);
  s.points_.reserve(64);
  s.cache_valid_ = 0;
  // Apply the last point again so that a non-dominant current input is wiped out properly.
  const double last = s.points_.back();
  s.apply(last);
  return s;
}

void PreisachState::reset(const PreisachGrid& grid) {
  lo_ = grid.lo;
  hi_ = grid.hi;
  points_.resize(1);
  points_[0] = lo_;
  cache_valid_ = 0;
  cache_owner_ = 0;
}

void PreisachState::apply(double u) {
  u = std::clamp(u, lo_, hi_);
  std::size_t n = points_.size() - 1;
  // Cached Everett term k depends on points k-1 and k; terms below the top stay valid
  // unless wiping-out rewrites an earlier point.
  if (n == 0) {
    if (u > points_[0]) points_.push_back(u);
    return;
  }
  const double top = points_[n];
  const bool rising = n % 2 == 1;
  if (u == top) return;
  if ((u > top) == rising) {
    points_[n] = u;  // same direction: move the current extremum
    invalidate_from(n - 1);
  } else {
    points_.push_back(u);  // reversal: the old input becomes a turning point
    ++n;
    invalidate_from(n - 1);
  }
  // Wiping-out: the input passing an earlier extremum of its kind erases that extremum and
  // the one between them.
  while (n >= 2) {
    const bool up = n % 2 == 1;
    const double prev = points_[n - 2];
    if (up ? u < prev : u > prev) break;
    points_[n - 2] = u;
    points_.resize(n - 1);
    n -= 2;
    invalidate_from(n >= 1 ? n - 1 : 0);
  }
  if (n == 0) {
    points_[0] = lo_;
    invalidate_from(0);
  }
}

// ---------------------------------------------------------------- model

namespace {
std::atomic<std::uint64_t> next_model_id{1};
}  // namespace

PreisachModel::PreisachModel(PreisachGrid grid, Eigen::VectorXd weights, double bias)
    : grid_(grid), weights_(std::move(weights)), bias_(bias), id_(next_model_id++) {
  grid_.validate();
  const int L = grid_.levels;
  if (weights_.size() != grid_.cells()) {
    throw_invalid("Preisach model with L = {} needs {} weights, got {}", L, grid_.cells(),
                  weights_.size());
  }
  if (!weights_.allFinite() || !std::isfinite(bias_)) throw_invalid("non-finite Preisach weight");
  w_ = Eigen::MatrixXd::Zero(L + 1, L + 1);
  for (int i = 0; i < L; ++i) {
    for (int j = i; j < L; ++j) w_(i, j) = weights_[grid_.cell_index(i, j)];
  }
  node_ = Eigen::MatrixXd::Zero(L + 1, L + 1);
  for (int J = 1; J <= L; ++J) {
    double column = 0.0;  // sum_{i=I..J-1} w(i, J-1), grown as I falls
    for (int I = J - 1; I >= 0; --I) {
      column += w_(I, J - 1);
      node_(J, I) = node_(J - 1, I) + column;
    }
  }
  rowpre_ = Eigen::MatrixXd::Zero(L + 1, L + 1);
  colpre_ = Eigen::MatrixXd::Zero(L + 1, L + 1);
  for (int I = 0; I <= L; ++I) {
    for (int j = I + 1; j <= L; ++j) rowpre_(I, j) = rowpre_(I, j - 1) + w_(I, j);
  }
  for (int J = 0; J <= L; ++J) {
    for (int i = J - 1; i >= 0; --i) colpre_(J, i) = colpre_(J, i + 1) + w_(i, J);
  }
  total_ = node_(L, 0);
}

Eigen::VectorXd PreisachModel::density() const {
  Eigen::VectorXd mu(weights_.size());
  const double h2 = grid_.step() * grid_.step();
  for (int i = 0; i < grid_.levels; ++i) {
    for (int j = i; j < grid_.levels; ++j) {
      const int k = grid_.cell_index(i, j);
      mu[k] = weights_[k] / (h2 * PreisachGrid::relative_area(i, j));
    }
  }
  return mu;
}

double PreisachModel::everett(double a, double b) const {
  const int L = grid_.levels;
  const double inv_h = L / (grid_.hi - grid_.lo);
  const double ta = std::clamp((a - grid_.lo) * inv_h, 0.0, static_cast<double>(L));
  const double tb = std::clamp((b - grid_.lo) * inv_h, 0.0, static_cast<double>(L));
  if (!(tb < ta)) return 0.0;
  const int J = std::min(static_cast<int>(ta), L - 1);
  const int I = std::min(static_cast<int>(tb), L - 1);
  const double fa = ta - J;
  const double fb = tb - I;
  if (I == J) return w_(I, I) * (fa - fb) * (fa - fb);
  const double gb = 1.0 - fb;
  return node_(J, I + 1) + gb * rowpre_(I, J - 1) + fa * colpre_(J, I + 1) + w_(I, J) * gb * fa +
         w_(I, I) * gb * gb + w_(J, J) * fa * fa;
}

double PreisachModel::output(const PreisachState& state) const {
  // mu(+) = sum_{k=1..n} (-1)^(k+1) E(max(s_{k-1}, s_k), min(s_{k-1}, s_k)); the terms below
  // the top one are cached in the state as prefix sums.
  const std::vector<double>& s = state.points_;
  const std::size_t n = s.size() - 1;
  if (n == 0) return bias_ - total_;
  auto term = [&](std::size_t k) {
    return k % 2 == 1 ? everett(s[k], s[k - 1]) : -everett(s[k - 1], s[k]);
  };
  std::vector<double>& prefix = state.prefix_;
  if (state.cache_owner_ != id_) {
    state.cache_owner_ = id_;
    state.cache_valid_ = 0;
  }
  if (prefix.size() < n) prefix.resize(std::max<std::size_t>(n, 2 * prefix.size()));
  prefix[0] = 0.0;
  for (std::size_t k = state.cache_valid_ + 1; k < n; ++k) prefix[k] = prefix[k - 1] + term(k);
  state.cache_valid_ = n - 1;
  return bias_ + 2.0 * (prefix[n - 1] + term(n)) - total_;
}

Eigen::VectorXd PreisachModel::simulate(PreisachState& state, std::span<const double> input) const {
  Eigen::VectorXd y(static_cast<Eigen::Index>(input.size()));
  for (std::size_t t = 0; t < input.size(); ++t)
    y[static_cast<Eigen::Index>(t)] = step(state, input[t]);
  return y;
}

PreisachModel PreisachModel::with_input_scale(double scale) const {
  if (!(scale > 0.0) || !std::isfinite(scale))
    throw_invalid("input scale must be > 0, got {}", scale);
  PreisachGrid g = grid_;
  g.lo /= scale;
  g.hi /= scale;
  return PreisachModel(g, weights_, bias_);
}

PreisachModel PreisachModel::with_output_affine(double gain, double offset) const {
  return PreisachModel(grid_, weights_ * gain, bias_ * gain + offset);
}

PreisachModel average_on_fine_grid(std::span<const PreisachModel> models,
                                   const PreisachGrid& fine) {
  fine.validate();
  if (models.empty()) throw_invalid("average_on_fine_grid: no models");
  const double hf = fine.step();
  Eigen::VectorXd w = Eigen::VectorXd::Zero(fine.cells());
  double bias = 0.0;
  auto on_lattice = [&](double x, const char* what) {
    const double t = (x - fine.lo) / hf;
    const double r = std::round(t);
    if (std::abs(t - r) > 1e-6 || r < -1e-9 || r > fine.levels + 1e-9) {
      throw_invalid("average_on_fine_grid: {} {} is not a node of the fine grid", what, x);
    }
    return static_cast<int>(r);
  };
  for (const PreisachModel& m : models) {
    const PreisachGrid& g = m.grid();
    const int a0 = on_lattice(g.lo, "lo");
    const int S = on_lattice(fine.lo + g.step(), "step");
    if (S < 1 || std::abs(S * hf - g.step()) > 1e-9 * g.step()) {
      throw_invalid("average_on_fine_grid: step {} is not a multiple of {}", g.step(), hf);
    }
    if (a0 + g.levels * S > fine.levels)
      throw_invalid("average_on_fine_grid: model reaches beyond the fine grid");
    const double S2 = static_cast<double>(S) * S;
    for (int i = 0; i < g.levels; ++i) {
      for (int j = i; j < g.levels; ++j) {
        const double mass = m.weights()[g.cell_index(i, j)];
        if (mass == 0.0) continue;
        for (int s = 0; s < S; ++s) {
          for (int t = (i == j ? s : 0); t < S; ++t) {
            const int fi = a0 + i * S + s, fj = a0 + j * S + t;
            // Off-diagonal coarse cell: S^2 equal squares. Diagonal coarse triangle: squares
            // of twice the mass of the S fine diagonal triangles.
            const double share = i != j ? 1.0 / S2 : (s == t ? 1.0 / S2 : 2.0 / S2);
            w[fine.cell_index(fi, fj)] += mass * share;
          }
        }
      }
    }
    bias += m.bias();
  }
  const double n = static_cast<double>(models.size());
  return PreisachModel(fine, w / n, bias / n);
}

// ---------------------------------------------------------------- regressor

void signed_area_fractions(const PreisachGrid& grid, const PreisachState& state,
                           Eigen::Ref<Eigen::VectorXd> row) {
  const int L = grid.levels;
  if (row.size() != grid.cells()) throw_invalid("regressor row needs {} entries", grid.cells());
  const double h = grid.step();
  const double lo = grid.lo;
  row.setZero();  // accumulates the +1 area, in units of h^2
  const auto s = state.turning_points();
  const std::size_t n = s.size() - 1;
  // Staircase boundary: for alpha in [M_{k+1}, M_k) the +1 part is beta < m_k. Walk the
  // pieces from low alpha upwards (k from the innermost pair outwards).
  double a_from = lo;
  for (std::size_t idx = (n % 2 == 1 ? n : n - 1); idx >= 1 && idx <= n; idx -= 2) {
    const double M = s[idx];
    const double m = idx + 1 <= n ? s[idx + 1] : s[idx];
    const double a_to = M;
    if (a_to > a_from && m > lo) {
      const int j0 = std::clamp(static_cast<int>((a_from - lo) / h), 0, L - 1);
      const int j1 = std::clamp(static_cast<int>(std::ceil((a_to - lo) / h)) - 1, 0, L - 1);
      for (int j = j0; j <= j1; ++j) {
        const double xj = lo + j * h;
        const double a0 = std::max(a_from, xj);
        const double a1 = std::min(a_to, xj + h);
        if (!(a1 > a0)) continue;
        const double len = a1 - a0;
        for (int i = 0; i < j; ++i) {
          const double xi = lo + i * h;
          if (m <= xi) break;
          row[grid.cell_index(i, j)] += len * std::min(m - xi, h) / (h * h);
        }
        // Diagonal cell: beta in [x_j, alpha], +1 for beta < m.
        double area;
        if (m >= a1) {
          area = 0.5 * ((a1 - xj) * (a1 - xj) - (a0 - xj) * (a0 - xj));
        } else if (m <= a0) {
          area = len * std::max(m - xj, 0.0);
        } else {
          area = 0.5 * ((m - xj) * (m - xj) - (a0 - xj) * (a0 - xj)) + (a1 - m) * (m - xj);
        }
        row[grid.cell_index(j, j)] += area / (0.5 * h * h);
      }
    }
    a_from = std::max(a_from, a_to);
    if (idx < 2) break;
  }
  for (Eigen::Index k = 0; k < row.size(); ++k) row[k] = 2.0 * std::clamp(row[k], 0.0, 1.0) - 1.0;
}

Eigen::MatrixXd regressor_matrix(const PreisachGrid& grid, PreisachState& state,
                                 std::span<const double> input) {
  Eigen::MatrixXd A(static_cast<Eigen::Index>(input.size()), grid.cells());
  Eigen::VectorXd row(grid.cells());
  for (std::size_t t = 0; t < input.size(); ++t) {
    state.apply(input[t]);
    signed_area_fractions(grid, state, row);
    A.row(static_cast<Eigen::Index>(t)) = row.transpose();
  }
  return A;
}

}  // namespace scpkit
