#include "stats.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace scpkit::diagnosis {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  if (v.size() % 2 == 1) return *mid;
  // An even count: the mean of the two middle values, so that median(-v) = -median(v) (the
  // upper one alone made a spike among two hold-mates count from the higher of them, and every
  // robust scale differ with the response's sign convention).
  return 0.5 * (*std::max_element(v.begin(), mid) + *mid);
}

double mad(const std::vector<double>& v) {
  const double m = median(v);
  std::vector<double> d;
  d.reserve(v.size());
  for (double x : v) d.push_back(std::abs(x - m));
  return 1.4826 * median(d);
}

std::pair<double, double> masked_line(std::span<const double> x, std::span<const double> y,
                                      const std::vector<char>& use,
                                      std::optional<double> fixed_slope) {
  LineSums sums;
  for (std::size_t t = 0; t < x.size(); ++t) {
    if (use[t]) sums.add(x[t], y[t]);
  }
  const double b = fixed_slope ? *fixed_slope : sums.slope();
  return {b, sums.intercept(b)};
}

double training_sse(std::span<const double> y, std::span<const double> p,
                    const std::vector<char>& train) {
  double ss = 0.0;
  for (std::size_t t = 0; t < y.size(); ++t) {
    if (train[t]) ss += (y[t] - p[t]) * (y[t] - p[t]);
  }
  return ss;
}

double rms(std::span<const double> e) {
  double s = 0.0;
  for (double x : e) s += x * x;
  return e.empty() ? 0.0 : std::sqrt(s / static_cast<double>(e.size()));
}

double trimmed_sigma(std::vector<double> sq, std::size_t drop_one_in, double ratio) {
  std::sort(sq.begin(), sq.end());
  const std::size_t keep = sq.size() - sq.size() / drop_one_in;
  const double mean_sq =
      std::accumulate(sq.begin(), sq.begin() + static_cast<std::ptrdiff_t>(keep), 0.0) /
      static_cast<double>(keep);
  return std::sqrt(mean_sq) / ratio;
}

double quantisation_step(std::span<const double> y) {
  std::vector<double> v(y.begin(), y.end());
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  if (v.size() < 3) return 0.0;
  double q = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < v.size(); ++i) q = std::min(q, v[i] - v[i - 1]);
  int whole = 0;
  for (std::size_t i = 1; i < v.size(); ++i) {
    const double k = (v[i] - v[i - 1]) / q;
    whole += std::abs(k - std::round(k)) < 0.05 ? 1 : 0;
  }
  return whole >= 0.9 * static_cast<double>(v.size() - 1) ? q : 0.0;
}

double r_squared(const Eigen::VectorXd& r, const Eigen::MatrixXd& X) {
  Eigen::MatrixXd A(r.size(), X.cols() + 1);
  A.col(0).setOnes();
  A.rightCols(X.cols()) = X;
  const Eigen::VectorXd beta = A.colPivHouseholderQr().solve(r);
  const double ss_res = (r - A * beta).squaredNorm();
  const double ss_tot = (r.array() - r.mean()).square().sum();
  return ss_tot > 0.0 ? std::max(0.0, 1.0 - ss_res / ss_tot) : 0.0;
}

double block_permutation_p(const Eigen::VectorXd& r, double observed, std::size_t block,
                           int permutations, std::mt19937_64& rng,
                           const std::function<double(const Eigen::VectorXd&)>& statistic) {
  const auto n = static_cast<std::size_t>(r.size());
  std::vector<std::size_t> starts;
  for (std::size_t s = 0; s < n; s += block) starts.push_back(s);
  int exceed = 0;
  Eigen::VectorXd perm(r.size());
  for (int i = 0; i < permutations; ++i) {
    std::shuffle(starts.begin(), starts.end(), rng);
    Eigen::Index k = 0;
    for (std::size_t s : starts) {
      for (std::size_t t = s; t < std::min(s + block, n); ++t)
        perm[k++] = r[static_cast<Eigen::Index>(t)];
    }
    exceed += statistic(perm) >= observed ? 1 : 0;
  }
  return (1.0 + exceed) / (1.0 + permutations);
}

double block_permutation_p(const Eigen::VectorXd& r, const Eigen::MatrixXd& X, double r2,
                           std::size_t block, int permutations, std::mt19937_64& rng) {
  // The projection onto [1, X] is computed once; each permutation costs one product.
  Eigen::MatrixXd A(r.size(), X.cols() + 1);
  A.col(0).setOnes();
  A.rightCols(X.cols()) = X;
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  return block_permutation_p(r, r2, block, permutations, rng, [&](const Eigen::VectorXd& perm) {
    const double ss_res = (perm - A * qr.solve(perm)).squaredNorm();
    const double ss_tot = (perm.array() - perm.mean()).square().sum();
    return ss_tot > 0.0 ? 1.0 - ss_res / ss_tot : 0.0;
  });
}

double sign_flip_p(const std::vector<double>& d, int permutations, std::mt19937_64& rng) {
  double observed = 0.0;
  for (double x : d) observed += x;
  if (d.empty() || observed <= 0.0) return 1.0;
  int exceed = 0, total = 0;
  auto count = [&](std::uint64_t signs) {
    double s = 0.0;
    for (std::size_t b = 0; b < d.size(); ++b) s += (signs >> b & 1U) ? -d[b] : d[b];
    exceed += s >= observed - 1e-12 * std::abs(observed) ? 1 : 0;
    ++total;
  };
  if (d.size() <= 12) {
    for (std::uint64_t m = 0; m < (std::uint64_t{1} << d.size()); ++m) count(m);
    return static_cast<double>(exceed) / total;
  }
  std::uniform_int_distribution<std::uint64_t> bits;
  for (int i = 0; i < permutations; ++i) {
    double s = 0.0;
    for (std::size_t b = 0; b < d.size(); ++b) s += (bits(rng) & 1U) ? -d[b] : d[b];
    exceed += s >= observed - 1e-12 * std::abs(observed) ? 1 : 0;
  }
  return (1.0 + exceed) / (1.0 + permutations);
}

}  // namespace scpkit::diagnosis
