#pragma once
// Private to diagnose: robust statistics and the two resampling tests that respect the
// residuals' autocorrelation (blocks of consecutive readings move as units).
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <random>
#include <span>
#include <vector>

namespace scpkit::diagnosis {

double median(std::vector<double> v);      ///< of an even count, the mean of the middle two
double mad(const std::vector<double>& v);  ///< 1.4826 median |v - median| (sigma if Gaussian)
double rms(std::span<const double> e);

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
