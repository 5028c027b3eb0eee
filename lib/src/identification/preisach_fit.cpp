#include "scpkit/identification/preisach_fit.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <utility>

#include "scpkit/error.hpp"
#include "util/parallel.hpp"

namespace scpkit {
namespace {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The linear problem for one grid: per-block normal equations of [sign * S, 1] (and, with the
// reversible term, sign * (u - lo) / (hi - lo)) and the smoothness penalty matrix. Unknowns:
// cell masses (times sign), the bias, then r (times sign). The regressors are stored by
// reading, each row contiguous: rows are written, compared, combined into the Gram matrix and
// multiplied one at a time.
struct Design {
  PreisachGrid grid;
  RowMajorMatrix A;                   // N x (cells + 1 + reversible)
  std::vector<Eigen::MatrixXd> gram;  // per block, unscaled A_b' A_b
  std::vector<Eigen::VectorXd> rhs;   // per block, A_b' y_b
  std::vector<int> rows;              // per block, sample count
  Eigen::MatrixXd penalty;            // unknowns^2, L^4 / N_pairs * D'D
  int unexcited = 0;
  int rank = 0;  // numerical rank of the regressor
  int unknowns() const { return static_cast<int>(A.cols()); }
};

Eigen::MatrixXd smoothness_penalty(const PreisachGrid& grid, int unknowns) {
  const int L = grid.levels;
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(unknowns, unknowns);
  int pairs = 0;
  auto add = [&](int i0, int j0, int i1, int j1) {
    const int a = grid.cell_index(i0, j0), b = grid.cell_index(i1, j1);
    const double ca = 1.0 / PreisachGrid::relative_area(i0, j0);
    const double cb = 1.0 / PreisachGrid::relative_area(i1, j1);
    R(a, a) += ca * ca;
    R(b, b) += cb * cb;
    R(a, b) -= ca * cb;
    R(b, a) -= ca * cb;
    ++pairs;
  };
  for (int i = 0; i < L; ++i) {
    for (int j = i; j < L; ++j) {
      if (i + 1 <= j) add(i, j, i + 1, j);
      if (j + 1 < L) add(i, j, i, j + 1);
    }
  }
  if (pairs > 0) R *= std::pow(static_cast<double>(L), 4) / pairs;
  return R;
}

// The most dimensions a run of rows is combined in (combine_run); a Kelvin element's readings
// in one hold span two (the hold's regressors and the state they relax from).
constexpr Eigen::Index kMaxRunRank = 4;

// Writes rows whose Gram matrix and right-hand side are those of the rows `run` of A against y,
// into the columns of AbT from `at` on (yb alike), and returns how many. Equal rows a, k of them,
// give one: sqrt(k) a against (y_1 + ... + y_k) / sqrt(k). Rows R = C Q in a space of r < k
// dimensions (Q: r orthonormal rows, by Gram-Schmidt) give r: their Gram matrix is Q' C'C Q and
// right-hand side Q' C' y, so with C = U T the rows T Q against U'y give both. Exact to
// round-off: a row is taken as in the space when what Gram-Schmidt leaves of it is below 1e-12 of
// its norm. Other runs are written as they are. The Gram product, the fit's largest cost, shrinks
// by the readings per hold.
Eigen::Index combine_run(const RowMajorMatrix& A, const Eigen::Ref<const Eigen::VectorXd>& y,
                         const std::vector<Eigen::Index>& run, Eigen::MatrixXd& AbT,
                         Eigen::VectorXd& yb, Eigen::Index at) {
  const auto k = static_cast<Eigen::Index>(run.size());
  auto as_they_are = [&] {
    for (Eigen::Index i = 0; i < k; ++i) {
      AbT.col(at + i) = A.row(run[static_cast<std::size_t>(i)]).transpose();
      yb[at + i] = y[run[static_cast<std::size_t>(i)]];
    }
    return k;
  };
  if (k == 1) return as_they_are();
  const auto equal = [&] {
    for (Eigen::Index i = 1; i < k; ++i) {
      if (A.row(run[static_cast<std::size_t>(i)]) != A.row(run[0])) return false;
    }
    return true;
  };
  if (equal()) {
    const double w = std::sqrt(static_cast<double>(k));
    double sum = 0.0;
    for (Eigen::Index t : run) sum += y[t];
    AbT.col(at) = w * A.row(run[0]).transpose();
    yb[at] = sum / w;
    return 1;
  }
  const Eigen::Index m = A.cols();
  Eigen::MatrixXd Q(m, kMaxRunRank);  // orthonormal columns, the first r in use
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(k, kMaxRunRank);
  Eigen::Index r = 0;
  for (Eigen::Index i = 0; i < k; ++i) {
    const auto x = A.row(run[static_cast<std::size_t>(i)]).transpose();
    Eigen::VectorXd rest = x;
    for (int pass = 0; pass < 2; ++pass) {  // twice is enough (Kahan-Parlett)
      const Eigen::VectorXd c = Q.leftCols(r).transpose() * rest;
      C.row(i).head(r) += c.transpose();
      rest -= Q.leftCols(r) * c;
    }
    const double left = rest.norm();
    if (left <= 1e-12 * x.norm()) continue;
    if (r == kMaxRunRank) return as_they_are();
    Q.col(r) = rest / left;
    C(i, r) = left;
    ++r;
  }
  if (r >= k) return as_they_are();
  Eigen::VectorXd yr(k);
  for (Eigen::Index i = 0; i < k; ++i) yr[i] = y[run[static_cast<std::size_t>(i)]];
  // C = U T (Householder; T r x r upper triangular): C'C = T'T and C'y = T' (U'y), so the
  // rows are T Q against the first r entries of U'y. No C'C is formed: its condition is C's
  // squared, and a reading that only just leaves the space would make it singular.
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(C.leftCols(r));
  const Eigen::MatrixXd T = qr.matrixQR().topRows(r).triangularView<Eigen::Upper>();
  AbT.middleCols(at, r) = Q.leftCols(r) * T.transpose();
  yb.segment(at, r) = (qr.householderQ().transpose() * yr).head(r);
  return r;
}

Design make_design(const PreisachGrid& grid, int sign, std::span<const double> input,
                   std::span<const double> output, const std::vector<int>& block_of, int nblocks,
                   bool with_rank, bool restart, const std::vector<int>& segment_of,
                   const std::function<void(Eigen::Ref<Eigen::VectorXd>)>& filter,
                   const std::optional<std::pair<double, double>>& cycle,
                   const std::optional<std::pair<double, double>>& reversible) {
  Design d;
  d.grid = grid;
  const auto n = static_cast<Eigen::Index>(input.size());
  const int p = grid.cells();
  auto initial = [&] {
    return cycle ? PreisachState::after_cycle(grid, cycle->first, cycle->second)
                 : PreisachState::negative_saturation(grid);
  };
  PreisachState state = initial();
  const int m = p + 1 + (reversible ? 1 : 0);
  d.A.resize(n, m);
  Eigen::VectorXd row(p);
  // in_hold[t]: reading t has the input and memory of reading t - 1 (a later reading in the
  // same hold), so its regressors before any filter are those of source[t], its hold's first.
  std::vector<char> in_hold(static_cast<std::size_t>(n), 0);
  std::vector<Eigen::Index> source(static_cast<std::size_t>(n));
  for (Eigen::Index t = 0; t < n; ++t) {
    const auto i = static_cast<std::size_t>(t);
    const bool restarts = restart && t > 0 && segment_of[i] != segment_of[i - 1];
    if (restarts) state = initial();
    // The same input again leaves the memory as it was (a reading later in the same hold).
    if (t > 0 && !restarts && input[i] == input[i - 1]) {
      in_hold[i] = 1;
      source[i] = source[i - 1];
      continue;
    }
    source[i] = t;
    state.apply(input[i]);
    signed_area_fractions(grid, state, row);
    d.A.row(t).head(p) = row.transpose() * static_cast<double>(sign);
  }
  d.A.col(p).setOnes();
  if (reversible) {
    const auto [lo, hi] = *reversible;
    for (Eigen::Index t = 0; t < n; ++t) d.A(t, p + 1) = sign * (input[t] - lo) / (hi - lo);
  }
  if (filter) {
    // The filter takes one column at a time, contiguous: eight columns are copied out together
    // (each row's eight values one cache line; a reading later in a hold from its hold's first),
    // filtered and copied back into every row.
    constexpr Eigen::Index kAtOnce = 8;
    Eigen::MatrixXd cols(n, kAtOnce);
    for (Eigen::Index k0 = 0; k0 < m; k0 += kAtOnce) {
      const Eigen::Index w = std::min(kAtOnce, m - k0);
      for (Eigen::Index t = 0; t < n; ++t)
        cols.row(t).head(w) = d.A.row(source[static_cast<std::size_t>(t)]).segment(k0, w);
      for (Eigen::Index k = 0; k < w; ++k) filter(cols.col(k));
      for (Eigen::Index t = 0; t < n; ++t) d.A.row(t).segment(k0, w) = cols.row(t).head(w);
    }
  } else {
    for (Eigen::Index t = 0; t < n; ++t) {
      if (in_hold[static_cast<std::size_t>(t)])
        d.A.row(t).head(p) = d.A.row(source[static_cast<std::size_t>(t)]).head(p);
    }
  }
  // Cells whose column does not change (never switched), by one pass over the rows.
  Eigen::VectorXd lowest = Eigen::VectorXd::Constant(p, std::numeric_limits<double>::infinity());
  Eigen::VectorXd highest = -lowest;
  for (Eigen::Index t = 0; t < n; ++t) {
    lowest = lowest.cwiseMin(d.A.row(t).head(p).transpose());
    highest = highest.cwiseMax(d.A.row(t).head(p).transpose());
  }
  d.unexcited = static_cast<int>((!((highest - lowest).array() >= 1e-9)).count());
  const Eigen::Map<const Eigen::VectorXd> y(output.data(), n);
  d.gram.assign(nblocks, Eigen::MatrixXd::Zero(m, m));
  d.rhs.assign(nblocks, Eigen::VectorXd::Zero(m));
  d.rows.assign(nblocks, 0);
  for (int b = 0; b < nblocks; ++b) {
    std::vector<Eigen::Index> idx;
    for (Eigen::Index t = 0; t < n; ++t) {
      if (block_of[t] == b) idx.push_back(t);
    }
    d.rows[b] = static_cast<int>(idx.size());
    if (idx.empty()) continue;
    // Runs of consecutive rows that enter the Gram matrix together: rows equal to the one
    // before, and the readings of one hold (equal before a time filter, which moves them in a
    // space of few dimensions).
    std::vector<std::pair<std::size_t, std::size_t>> runs;  // [first, last] in idx
    for (std::size_t r = 0; r < idx.size(); ++r) {
      const bool joins =
          r > 0 && (d.A.row(idx[r]) == d.A.row(idx[r - 1]) ||
                    (idx[r] == idx[r - 1] + 1 && in_hold[static_cast<std::size_t>(idx[r])]));
      if (joins)
        runs.back().second = r;
      else
        runs.emplace_back(r, r);
    }
    Eigen::MatrixXd AbT(m, static_cast<Eigen::Index>(idx.size()));
    Eigen::VectorXd yb(static_cast<Eigen::Index>(idx.size()));
    Eigen::Index used = 0;
    for (const auto& [first, last] : runs) {
      std::vector<Eigen::Index> run(idx.begin() + static_cast<std::ptrdiff_t>(first),
                                    idx.begin() + static_cast<std::ptrdiff_t>(last) + 1);
      used += combine_run(d.A, y, run, AbT, yb, used);
    }
    d.gram[b].selfadjointView<Eigen::Lower>().rankUpdate(AbT.leftCols(used));
    d.gram[b] = d.gram[b].selfadjointView<Eigen::Lower>();
    d.rhs[b] = AbT.leftCols(used) * yb.head(used);
  }
  d.penalty = smoothness_penalty(grid, m);
  if (!with_rank) return d;
  // Numerical rank of the regressor from the pivoted LDL' of its Gram matrix.
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(m, m);
  for (const auto& g : d.gram) G += g;
  const Eigen::VectorXd piv = G.ldlt().vectorD().cwiseAbs();
  const double pmax = piv.maxCoeff();
  d.rank = static_cast<int>((piv.array() > 1e-10 * pmax).count());
  return d;
}

// Fits on every block except `skip` (-1: all blocks).
NnlsResult solve_design(const Design& d, double lambda, int skip, const NnlsOptions& nnls,
                        const Eigen::VectorXd& warm = Eigen::VectorXd()) {
  const int p = d.grid.cells();
  const int m = d.unknowns();
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(m);
  int rows = 0;
  for (std::size_t b = 0; b < d.gram.size(); ++b) {
    if (static_cast<int>(b) == skip) continue;
    G += d.gram[b];
    f += d.rhs[b];
    rows += d.rows[b];
  }
  const double inv_n = 1.0 / std::max(rows, 1);
  G *= inv_n;
  f *= inv_n;
  G += lambda * d.penalty;
  std::vector<bool> constrained(static_cast<std::size_t>(m), true);
  constrained[p] = false;  // the bias; the reversible term, like the cells, has the sign
  return solve_nnls(G, f, constrained, nnls, warm);
}

// Grid k of S shifted grids: the base grid moved down by k h / S, one level longer for k > 0
// so that every shifted grid still covers [lo, hi].
PreisachGrid shifted_grid(const PreisachGrid& base, int L, int k, int S) {
  const double h = (base.hi - base.lo) / L;
  PreisachGrid g;
  g.levels = L + (k > 0 ? 1 : 0);
  g.lo = base.lo - k * h / S;
  g.hi = g.lo + g.levels * h;
  return g;
}

// The common fine grid of S shifted grids (step h / S).
PreisachGrid fine_grid(const PreisachGrid& base, int L, int S) {
  if (S == 1) return PreisachGrid{base.lo, base.hi, L};
  const double h = (base.hi - base.lo) / L;
  return PreisachGrid{base.lo - (S - 1) * h / S, base.lo + (L + 1) * h, (L + 1) * S + S - 1};
}

// Blocks that may be held out: those whose input range the other blocks cover, so that the
// score measures interpolation, not extrapolation beyond the identified input range (a
// block holding the only excursion to the input maximum always stays in training).
std::vector<char> heldout_eligible(std::span<const double> input, const std::vector<int>& block_of,
                                   int nblocks) {
  std::vector<double> lo(nblocks, std::numeric_limits<double>::infinity());
  std::vector<double> hi(nblocks, -std::numeric_limits<double>::infinity());
  for (std::size_t t = 0; t < input.size(); ++t) {
    if (block_of[t] < 0) continue;  // excluded row
    lo[block_of[t]] = std::min(lo[block_of[t]], input[t]);
    hi[block_of[t]] = std::max(hi[block_of[t]], input[t]);
  }
  std::vector<char> ok(nblocks, 0);
  int count = 0;
  for (int b = 0; b < nblocks; ++b) {
    double rest_lo = std::numeric_limits<double>::infinity(), rest_hi = -rest_lo;
    for (int o = 0; o < nblocks; ++o) {
      if (o == b) continue;
      rest_lo = std::min(rest_lo, lo[o]);
      rest_hi = std::max(rest_hi, hi[o]);
    }
    const double tol = 1e-9 * (std::abs(rest_hi) + std::abs(rest_lo) + 1.0);
    ok[b] = std::isfinite(lo[b]) && lo[b] >= rest_lo - tol && hi[b] <= rest_hi + tol;
    count += ok[b];
  }
  if (count < 2) std::fill(ok.begin(), ok.end(), 1);  // nothing better: hold out every block
  return ok;
}

// Held-out errors of the averaged shifted-grid model for every smoothness in `lambdas`
// (ascending; each solve warm-starts from the previous one): the pooled RMS (% of range) and
// each held-out block's sum of squares (blocks in one order for every design), for paired
// comparisons.
struct HeldoutErrors {
  std::vector<double> rms_pct;
  std::vector<std::vector<double>> block_sse;  ///< [lambda][held-out block]
};

HeldoutErrors heldout_errors(const std::vector<Design>& shifts, const std::vector<double>& lambdas,
                             const std::vector<int>& block_of, const std::vector<char>& eligible,
                             std::span<const double> output, double range, const NnlsOptions& nnls,
                             int threads) {
  // The held-out blocks and their rows, in one order for every design.
  std::vector<int> held;
  std::vector<std::vector<Eigen::Index>> rows_of;
  for (std::size_t b = 0; b < shifts.front().gram.size(); ++b) {
    if (shifts.front().rows[b] == 0 || !eligible[b]) continue;
    held.push_back(static_cast<int>(b));
    rows_of.emplace_back();
    for (Eigen::Index t = 0; t < shifts.front().A.rows(); ++t) {
      if (block_of[t] == static_cast<int>(b)) rows_of.back().push_back(t);
    }
  }
  // Each grid's share of the averaged prediction, [grid][held-out block][lambda][row]: the
  // grids are independent (each warm-starts its solves from its own previous lambda).
  const double S = static_cast<double>(shifts.size());
  std::vector<std::vector<std::vector<Eigen::VectorXd>>> share(shifts.size());
  detail::parallel_for(static_cast<int>(shifts.size()), threads, [&](int k) {
    const Design& d = shifts[static_cast<std::size_t>(k)];
    auto& mine = share[static_cast<std::size_t>(k)];
    mine.resize(held.size());
    for (std::size_t h = 0; h < held.size(); ++h) {
      const std::vector<Eigen::Index>& rows = rows_of[h];
      Eigen::VectorXd warm;
      for (double lambda : lambdas) {
        const NnlsResult r = solve_design(d, lambda, held[h], nnls, warm);
        warm = r.x;
        Eigen::VectorXd part(static_cast<Eigen::Index>(rows.size()));
        for (std::size_t i = 0; i < rows.size(); ++i)
          part[static_cast<Eigen::Index>(i)] = d.A.row(rows[i]).dot(r.x) / S;
        mine[h].push_back(std::move(part));
      }
    }
  });
  HeldoutErrors out;
  out.block_sse.assign(lambdas.size(), {});
  std::vector<double> sum_sq(lambdas.size(), 0.0);
  int count = 0;
  for (std::size_t h = 0; h < held.size(); ++h) {
    const std::vector<Eigen::Index>& rows = rows_of[h];
    count += static_cast<int>(rows.size());
    for (std::size_t l = 0; l < lambdas.size(); ++l) {
      Eigen::VectorXd pred = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(rows.size()));
      for (std::size_t k = 0; k < shifts.size(); ++k) pred += share[k][h][l];
      double sse = 0.0;
      for (std::size_t i = 0; i < rows.size(); ++i) {
        const double e = pred[static_cast<Eigen::Index>(i)] - output[rows[i]];
        sse += e * e;
        sum_sq[l] += e * e;
      }
      out.block_sse[l].push_back(sse);
    }
  }
  for (double sum : sum_sq)
    out.rms_pct.push_back(100.0 * std::sqrt(sum / std::max(count, 1)) / range);
  return out;
}

// Whether the per-block held-out errors `with` (a model one term larger) improve on `without`
// by more than one standard error of the paired differences: the one-standard-error rule. A
// significance test has no power over the three to five blocks of a short record (at 5 % a
// paired t-test refused the term on records half reversible whose held-out error it cut six-
// fold; docs/diagnose-log.md, session 36). A gain within round-off of the errors is none: a
// term whose coefficient sits at its bound in every fold leaves the errors equal but for the
// last digits, and the rule read those (a fresh voltage record's baseline took the term or
// not with the order of a sum; docs/diagnose-log.md, session 81). Nor is a gain that beats its
// standard error only by round-off: where one block gains d and the others are equal, the mean
// is d / m and so is the standard error, for any d and m, and the last digits of the blocks
// that did not change decided (session 82: a test record took the term or not with the order
// of the Gram product's sums). Ties go to the model without the term.
bool beats_by_one_se(const std::vector<double>& without, const std::vector<double>& with) {
  const std::size_t m = without.size();
  if (m < 2 || with.size() != m) return false;
  const auto md = static_cast<double>(m);
  double mean = 0.0, scale = 0.0;
  for (std::size_t b = 0; b < m; ++b) {
    mean += without[b] - with[b];
    scale += without[b];
  }
  mean /= md;
  scale /= md;
  double var = 0.0;
  for (std::size_t b = 0; b < m; ++b) {
    const double d = without[b] - with[b] - mean;
    var += d * d;
  }
  const double round_off = 1e-9 * scale;
  return mean > round_off && mean - std::sqrt(var / (md - 1.0) / md) > round_off;
}

}  // namespace

bool PreisachFitOptions::IsValid(std::string* why) const {
  auto fail = [&](std::string m) {
    if (why) *why = std::move(m);
    return false;
  };
  if (levels < 0 || levels > 400) return fail(fmt::format("levels must be 0..400, got {}", levels));
  if (levels == 0 && candidate_levels.empty()) return fail("no candidate levels to choose from");
  for (int L : candidate_levels) {
    if (L < 1 || L > 400) return fail(fmt::format("candidate level {} outside 1..400", L));
  }
  if (smoothness < 0.0 && candidate_smoothness.empty()) {
    return fail("no candidate smoothness to choose from");
  }
  for (double s : candidate_smoothness) {
    if (!(s >= 0.0) || !std::isfinite(s)) return fail("candidate smoothness must be >= 0");
  }
  if (!std::isfinite(smoothness)) return fail("smoothness must be finite");
  if (sign < -1 || sign > 1) return fail("sign must be -1, 0 or +1");
  if (lo && hi && !(*lo < *hi)) return fail("lo must be below hi");
  if (folds < 2) return fail("cross-validation needs at least 2 folds");
  if (grid_shifts < 1 || grid_shifts > 16) return fail("grid_shifts must be 1..16");
  if (threads < 1 || threads > 1024)
    return fail(fmt::format("threads must be 1..1024, got {}", threads));
  return true;
}

std::vector<int> cycle_blocks(std::span<const double> input, int folds) {
  const std::size_t n = input.size();
  std::vector<int> block(n, 0);
  if (n == 0 || folds < 2) return block;
  // Candidate cut points: local minima of the input (the start of a cycle).
  std::vector<std::size_t> cuts;
  for (std::size_t t = 1; t + 1 < n; ++t) {
    if (input[t] < input[t - 1] && input[t] <= input[t + 1]) cuts.push_back(t);
  }
  int b = 0;
  std::size_t start = 0;
  for (std::size_t c : cuts) {
    const double target = static_cast<double>(n) * (b + 1) / folds;
    if (b + 1 < folds && static_cast<double>(c) >= target) {
      for (std::size_t t = start; t < c; ++t) block[t] = b;
      start = c;
      ++b;
    }
  }
  for (std::size_t t = start; t < n; ++t) block[t] = b;
  // Too few cycles for whole-cycle blocks: fall back to contiguous equal parts.
  if (b + 1 < folds) {
    for (std::size_t t = 0; t < n; ++t) block[t] = static_cast<int>(t * folds / n);
  }
  return block;
}

PreisachFit fit_preisach(std::span<const double> input, std::span<const double> output,
                         std::span<const int> blocks, const PreisachFitOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InvalidArgument("Preisach fit options: " + why);
  const std::size_t n = input.size();
  if (output.size() != n) {
    throw_invalid("Preisach fit: {} inputs vs {} outputs", n, output.size());
  }
  if (!blocks.empty() && blocks.size() != n) throw_invalid("Preisach fit: block ids size");
  for (std::size_t t = 0; t < n; ++t) {
    if (!std::isfinite(input[t]) || !std::isfinite(output[t])) {
      throw IdentificationError(fmt::format("sample {} is not finite", t + 1));
    }
  }
  if (n < 8)
    throw IdentificationError(
        fmt::format("{} samples are too few to identify a Preisach model (need >= 8)", n));
  const auto [umin, umax] = std::minmax_element(input.begin(), input.end());
  const auto [ymin, ymax] = std::minmax_element(output.begin(), output.end());
  if (!(*umax > *umin)) throw IdentificationError("the input never changes: nothing to identify");
  const double range = *ymax - *ymin;
  if (!(range > 0.0)) throw IdentificationError("the response never changes: nothing to identify");

  PreisachGrid base;
  base.lo = options.lo.value_or(*umin);
  base.hi = options.hi.value_or(*umax);
  if (!(base.lo < base.hi)) throw IdentificationError("input range is empty after lo/hi");

  const int sign = options.sign != 0 ? options.sign : response_direction(input, output);

  // Blocks: the given segment ids (renumbered) or whole-cycle blocks.
  std::vector<int> block_of(n);
  int nblocks = 0;
  if (!blocks.empty()) {
    std::map<int, int> ids;
    for (int id : blocks) ids.emplace(id, 0);
    for (auto& [id, k] : ids) k = nblocks++;
    for (std::size_t t = 0; t < n; ++t) block_of[t] = ids[blocks[t]];
  }
  if (nblocks < 2) {
    block_of = cycle_blocks(input, options.folds);
    nblocks = *std::max_element(block_of.begin(), block_of.end()) + 1;
  }
  const std::vector<int> segment_of = block_of;  // for restarts: excluded rows keep their block
  if (!options.exclude.empty()) {
    if (options.exclude.size() != n)
      throw_invalid("Preisach fit: exclude mask needs one entry per sample");
    for (std::size_t t = 0; t < n; ++t) {
      if (options.exclude[t]) block_of[t] = -1;  // in the memory, not in the least squares
    }
  }

  PreisachFitSummary summary;
  summary.sign = sign;
  summary.folds_used = nblocks;
  std::vector<int> levels =
      options.levels > 0 ? std::vector<int>{options.levels} : options.candidate_levels;
  std::vector<double> lambdas = options.smoothness >= 0.0 ? std::vector<double>{options.smoothness}
                                                          : options.candidate_smoothness;
  const bool run_cv = levels.size() > 1 || lambdas.size() > 1 ||
                      options.reversible == PreisachFitOptions::Reversible::kChosen;
  // Never offer more unknowns than the data can carry: half the samples without
  // regularisation, twice the samples with it (the smoothness term adds the rest). The unknowns
  // are the cells, the constant and, where fitted, the reversible term's coefficient.
  auto too_big = [&](int L, double lambda, bool with_reversible) {
    const int cells = L * (L + 1) / 2;  // exact: L (L + 1) is even
    const double unknowns = cells + 1.0 + (with_reversible ? 1.0 : 0.0);
    return unknowns > (lambda > 0.0 ? 2.0 : 0.5) * static_cast<double>(n);
  };
  std::erase_if(levels, [&](int L) {
    return run_cv && too_big(L, *std::max_element(lambdas.begin(), lambdas.end()),
                             options.reversible == PreisachFitOptions::Reversible::kOn);
  });
  if (levels.empty()) levels = {std::max(1, std::min(options.candidate_levels.front(), 4))};
  const std::vector<char> eligible = heldout_eligible(input, block_of, nblocks);
  summary.heldout_blocks = static_cast<int>(std::count(eligible.begin(), eligible.end(), 1));

  const int S = options.grid_shifts;
  const bool restart = options.restart_at_blocks && !blocks.empty();
  std::optional<std::pair<double, double>> cycle;
  if (options.precondition) cycle = std::pair{base.lo, base.hi};
  using Reversible = PreisachFitOptions::Reversible;
  std::vector<bool> reversibles;
  if (options.reversible != Reversible::kOn) reversibles.push_back(false);
  if (options.reversible != Reversible::kOff) reversibles.push_back(true);
  auto designs_for = [&](int L, bool with_rank, bool with_reversible) {
    std::optional<std::pair<double, double>> reversible;
    if (with_reversible) reversible = std::pair{base.lo, base.hi};
    std::vector<Design> shifts(static_cast<std::size_t>(S));
    detail::parallel_for(S, options.threads, [&](int k) {
      shifts[static_cast<std::size_t>(k)] = make_design(
          shifted_grid(base, L, k, S), sign, input, output, block_of, nblocks, with_rank && k == 0,
          restart, segment_of, options.output_filter, cycle, reversible);
    });
    return shifts;
  };
  std::sort(lambdas.begin(), lambdas.end());
  int chosen_levels = levels.front();
  double chosen_lambda = lambdas.front();
  bool chosen_reversible = reversibles.front();
  if (run_cv) {
    // The best setting with and without the reversible term; kChosen takes the term only where
    // it beats the best without by more than one standard error over the held-out blocks.
    struct Best {
      double rms = std::numeric_limits<double>::infinity();
      int levels = 0;
      double lambda = 0.0;
      std::vector<double> block_sse;
    };
    std::array<Best, 2> best_by;  // [without, with]
    for (bool rev : reversibles) {
      Best& best = best_by[rev ? 1 : 0];
      for (int L : levels) {
        std::vector<double> lams;
        for (double lam : lambdas) {
          if (!too_big(L, lam, rev)) lams.push_back(lam);
        }
        if (lams.empty()) continue;
        const HeldoutErrors cv =
            heldout_errors(designs_for(L, false, rev), lams, block_of, eligible, output, range,
                           options.nnls, options.threads);
        for (std::size_t l = 0; l < lams.size(); ++l) {
          summary.cross_validation.push_back({L, lams[l], rev, cv.rms_pct[l]});
          if (cv.rms_pct[l] < best.rms) best = {cv.rms_pct[l], L, lams[l], cv.block_sse[l]};
        }
      }
    }
    const bool take_term = std::isfinite(best_by[1].rms) &&
                           (!std::isfinite(best_by[0].rms) ||
                            beats_by_one_se(best_by[0].block_sse, best_by[1].block_sse));
    const Best& best = best_by[take_term ? 1 : 0];
    if (std::isfinite(best.rms)) {
      chosen_levels = best.levels;
      chosen_lambda = best.lambda;
      chosen_reversible = take_term;
    }
    summary.cv_rms_pct_range = best.rms;
  }

  const std::vector<Design> shifts = designs_for(chosen_levels, true, chosen_reversible);
  std::vector<PreisachModel> models;
  Eigen::VectorXd fitted = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n));
  bool converged = true;
  std::string message;
  double reversible_coef = 0.0;
  std::vector<NnlsResult> solved(shifts.size());
  detail::parallel_for(S, options.threads, [&](int k) {
    solved[static_cast<std::size_t>(k)] =
        solve_design(shifts[static_cast<std::size_t>(k)], chosen_lambda, -1, options.nnls);
  });
  for (std::size_t k = 0; k < shifts.size(); ++k) {
    const Design& d = shifts[k];
    const NnlsResult& r = solved[k];
    const int p = d.grid.cells();
    models.emplace_back(d.grid, r.x.head(p) * static_cast<double>(sign), r.x[p]);
    if (chosen_reversible) reversible_coef += sign * r.x[p + 1] / static_cast<double>(S);
    fitted += d.A * r.x / static_cast<double>(S);
    converged = converged && r.converged;
    summary.nnls_iterations += r.iterations;
    summary.kkt_violation = std::max(summary.kkt_violation, r.kkt_violation);
    if (message.empty() || !r.converged) message = r.message;
  }
  PreisachModel model =
      S == 1 ? models.front() : average_on_fine_grid(models, fine_grid(base, chosen_levels, S));
  const Design& d = shifts.front();
  const int p = d.grid.cells();
  summary.levels = chosen_levels;
  summary.grid_shifts = S;
  summary.smoothness = chosen_lambda;
  summary.reversible = chosen_reversible;
  summary.cells = p;
  summary.unexcited_cells = d.unexcited;
  summary.unidentified_directions = d.unknowns() - d.rank;
  summary.termination = converged ? PreisachFitSummary::Termination::kConverged
                                  : PreisachFitSummary::Termination::kNoConvergence;
  {
    std::vector<double> measured, predicted;
    for (std::size_t t = 0; t < n; ++t) {
      if (block_of[t] < 0) continue;
      measured.push_back(output[t]);
      predicted.push_back(fitted[static_cast<Eigen::Index>(t)]);
    }
    summary.train = error_metrics(measured, predicted);
  }
  if (d.unexcited > 0) {
    summary.warnings.push_back(fmt::format(
        "{} of {} cells never switch in the data: {}", d.unexcited, p,
        chosen_lambda > 0.0 ? "their densities come from the smoothness term alone"
                            : "their densities are not identified (left at the NNLS choice); "
                              "use smoothness > 0 or richer excitation"));
  }
  if (summary.unidentified_directions > 0) {
    summary.warnings.push_back(fmt::format(
        "the data identify only {} of {} unknowns (cells + bias{}): cells that always switch "
        "together share their mass arbitrarily{}",
        d.rank, d.unknowns(), chosen_reversible ? " + reversible term" : "",
        chosen_lambda > 0.0 ? ", resolved here by the smoothness term" : ""));
  }
  if (!converged) summary.warnings.push_back(message);
  summary.message = message;
  return {std::move(model), std::move(summary), base.lo, base.hi, reversible_coef};
}

std::string PreisachFitSummary::BriefReport() const {
  std::string s = fmt::format(
      "Preisach fit: L = {}{} ({} cells, {} unexcited){}, smoothness {:g}, sign {:+d}, {}\n"
      "  identification: E_max {:.3f} %, E_RMS {:.3f} % of the response range",
      levels, grid_shifts > 1 ? fmt::format(", averaged over {} shifted grids", grid_shifts) : "",
      cells, unexcited_cells, reversible ? " + a reversible term" : "", smoothness, sign,
      termination == Termination::kConverged ? "converged" : "NOT converged", train.max_pct_range,
      train.rms_pct_range);
  if (cv_rms_pct_range >= 0.0) {
    s += fmt::format(
        "\n  cross-validated: {} of {} blocks held out in turn (blocks holding an input extreme "
        "stay in training), held-out "
        "E_RMS {:.3f} % of range",
        heldout_blocks, folds_used, cv_rms_pct_range);
  }
  for (const auto& w : warnings) s += "\n  warning: " + w;
  return s;
}

}  // namespace scpkit
