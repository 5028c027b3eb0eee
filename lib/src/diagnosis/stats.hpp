#pragma once
// Private to diagnose: robust statistics and the two resampling tests that respect the
// residuals' autocorrelation (blocks of consecutive readings move as units).
#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <span>
#include <utility>
#include <vector>

namespace scpkit::diagnosis {

double median(std::vector<double> v);      ///< of an even count, the mean of the middle two
double mad(const std::vector<double>& v);  ///< 1.4826 median |v - median| (sigma if Gaussian)
double rms(std::span<const double> e);

/// The scatter of deviations from their squares `sq`, blind to the few that are spikes: the
/// RMS without the largest 1 / `drop_one_in` of them, over `ratio` (that RMS's ratio to sigma
/// for a normal: 0.871 without the largest 5 %, 0.662 without the largest 20 %).
double trimmed_sigma(std::vector<double> sq, std::size_t drop_one_in = 20, double ratio = 0.871);

/// The sums of the least-squares line y ~ c + b x, accumulated row by row.
struct LineSums {
  double n = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0, syy = 0.0;
  void add(double x, double y) {
    n += 1.0;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    syy += y * y;
  }
  /// The least-squares slope b; 0 where x does not vary.
  double slope() const {
    const double vxx = sxx - sx * sx / n;
    return vxx > 0.0 ? (sxy - sx * sy / n) / vxx : 0.0;
  }
  /// The least-squares intercept c for the slope b.
  double intercept(double b) const { return (sy - b * sx) / std::max(n, 1.0); }
  /// The residual sum of squares at the least-squares line.
  double sse() const {
    const double vxx = sxx - sx * sx / n, vxy = sxy - sx * sy / n;
    return syy - sy * sy / n - (vxx > 0.0 ? vxy * vxy / vxx : 0.0);
  }
};

/// The least-squares line y = b x + c on the rows where use != 0: (b, c); with fixed_slope, b is
/// that and only c is fitted.
std::pair<double, double> masked_line(std::span<const double> x, std::span<const double> y,
                                      const std::vector<char>& use,
                                      std::optional<double> fixed_slope = std::nullopt);

/// Squared error of a prediction on the training rows (how extensions choose their parameters).
double training_sse(std::span<const double> y, std::span<const double> p,
                    const std::vector<char>& train);

/// Quantisation step of a signal: the smallest gap between distinct values when nearly every
/// gap is a whole multiple of it; 0 when the signal is not quantised.
double quantisation_step(std::span<const double> y);

/// R^2 of the least-squares regression of r on [1, X].
double r_squared(const Eigen::VectorXd& r, const Eigen::MatrixXd& X);

/// p-value of R^2(r ~ X) against a block-permutation null: contiguous blocks of r (of the
/// given length) shuffled as units, X fixed.
double block_permutation_p(const Eigen::VectorXd& r, const Eigen::MatrixXd& X, double r2,
                           std::size_t block, int permutations, std::mt19937_64& rng);

/// p-value of any statistic of r (larger = stronger) against the same null: `observed` is its
/// value on r, `statistic` is evaluated on each permutation.
double block_permutation_p(const Eigen::VectorXd& r, double observed, std::size_t block,
                           int permutations, std::mt19937_64& rng,
                           const std::function<double(const Eigen::VectorXd&)>& statistic);

/// One-sided p-value that the extension lowers the squared error: the per-block differences
/// d_b = SSE_before,b - SSE_after,b (blocks of consecutive held-out readings) against random
/// sign flips of the d_b (exact when there are few blocks).
double sign_flip_p(const std::vector<double>& block_gain, int permutations, std::mt19937_64& rng);

}  // namespace scpkit::diagnosis
