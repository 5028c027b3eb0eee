#pragma once
// Shared helpers for the tests: random models and input histories, and the error-message
// matcher (the CLI11/fmt habit of checking what an error says, not only its type).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "scpkit/hysteresis/gpi.hpp"
#include "scpkit/hysteresis/preisach.hpp"

#define EXPECT_THROW_MSG(statement, type, fragment)                                   \
  do {                                                                                \
    try {                                                                             \
      statement;                                                                      \
      ADD_FAILURE() << "expected " #type " containing '" << (fragment) << "'";        \
    } catch (const type& e) {                                                         \
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what(); \
    }                                                                                 \
  } while (0)

// The first line of a test that measures behaviour over many records (how often a hidden effect
// is named): it runs in the optimised build and skips itself under the sanitizers, where it
// would take CI past its 90 minutes. Why, and what still runs there: tests/README.md.
#ifdef SCPKIT_SANITIZED
#define SCPKIT_SKIP_UNDER_SANITIZERS() \
  GTEST_SKIP() << "behaviour over many records: run in the optimised build"
#else
#define SCPKIT_SKIP_UNDER_SANITIZERS() static_cast<void>(0)
#endif

namespace scpkit::testing {

/// A model with random non-negative cell masses (some exactly zero) and a random bias.
inline PreisachModel random_model(std::mt19937& rng, PreisachGrid grid) {
  std::uniform_real_distribution<double> mass(0.0, 1.0);
  std::bernoulli_distribution zero(0.2);
  Eigen::VectorXd w(grid.cells());
  for (Eigen::Index k = 0; k < w.size(); ++k) w[k] = zero(rng) ? 0.0 : mass(rng);
  return PreisachModel(grid, w, std::uniform_real_distribution<double>(-1.0, 1.0)(rng));
}

/// Paper 000's identified GPI envelopes (aR 1.100, bR 0.048, aL 1.236, bL 0.088), radii j/10,
/// random weights of one sign, on 0-5.1 V.
inline GpiModel paper_gpi(std::mt19937& rng, double sign) {
  GpiModel m;
  m.right = {1.100, 0.048};
  m.left = {1.236, 0.088};
  std::uniform_real_distribution<double> U(0.01, 0.3);
  for (int j = 0; j <= 10; ++j) {
    m.radii.push_back(j / 10.0);
    m.weights.push_back(sign * U(rng));
  }
  m.bias = 0.396;
  m.v_min = 0.0;
  m.v_max = 5.1;
  m.validate();
  return m;
}

/// A random input history inside [lo, hi] (sometimes beyond, to exercise clamping).
inline std::vector<double> random_history(std::mt19937& rng, const PreisachGrid& g, int n) {
  const double pad = 0.1 * (g.hi - g.lo);
  std::uniform_real_distribution<double> u(g.lo - pad, g.hi + pad);
  std::vector<double> v(static_cast<std::size_t>(n));
  for (double& x : v) x = u(rng);
  return v;
}

/// ../shared beside the checkout, or SCPKIT_SHARED_DIR; empty when absent.
inline std::filesystem::path shared_dir() {
  if (const char* env = std::getenv("SCPKIT_SHARED_DIR")) {
    if (std::filesystem::exists(env)) return env;
  }
  const std::filesystem::path p = std::filesystem::path(SCPKIT_SOURCE_DIR) / ".." / "shared";
  return std::filesystem::exists(p) ? p : std::filesystem::path{};
}

}  // namespace scpkit::testing
