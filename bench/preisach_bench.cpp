// Preisach forward step and identification (targets in ../shared/SPEC.md "Performance").
//   forward step, L = 20:                  >= 20 million input steps per second, one core
//   identification, L = 10, 300 rows:      <= 5 ms
//   identification, L = 40, 20 000 rows:   <= 2 s
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "scpkit/hysteresis/gpi.hpp"
#include "scpkit/hysteresis/inverse.hpp"
#include "scpkit/hysteresis/preisach.hpp"
#include "scpkit/identification/preisach_fit.hpp"

namespace {

using namespace scpkit;

PreisachModel random_model(int L, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  PreisachGrid g{0.0, 1.0, L};
  Eigen::VectorXd w(g.cells());
  for (Eigen::Index k = 0; k < w.size(); ++k) w[k] = U(rng);
  return PreisachModel(g, w, 0.1);
}

// A damped random walk of turning points with several readings per half cycle, like a
// quasi-static test: memory depth stays realistic (a few to a dozen extrema).
std::vector<double> test_like_input(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<double> u;
  double prev = 0.0;
  while (u.size() < n) {
    const double target = U(rng);
    const int steps = 2 + static_cast<int>(U(rng) * 8);
    for (int k = 1; k <= steps && u.size() < n; ++k)
      u.push_back(prev + (target - prev) * k / steps);
    prev = target;
  }
  return u;
}

// The model's response to u from negative saturation: the targets a compensator is asked to
// reach.
std::vector<double> preisach_targets(const PreisachModel& model, const std::vector<double>& u) {
  PreisachState plant = PreisachState::negative_saturation(model.grid());
  std::vector<double> targets;
  targets.reserve(u.size());
  for (double v : u) targets.push_back(model.step(plant, v));
  return targets;
}

void BM_PreisachForwardStep(benchmark::State& state) {
  const int L = static_cast<int>(state.range(0));
  const PreisachModel model = random_model(L, 1);
  const std::vector<double> u = test_like_input(1 << 16, 2);
  PreisachState s = PreisachState::negative_saturation(model.grid());
  std::size_t i = 0;
  double sink = 0.0;
  for ([[maybe_unused]] auto _ : state) {
    sink += model.step(s, u[i]);
    i = (i + 1) & (u.size() - 1);
  }
  benchmark::DoNotOptimize(sink);
  state.SetItemsProcessed(state.iterations());
  state.counters["depth"] = s.depth();
}
BENCHMARK(BM_PreisachForwardStep)->Arg(10)->Arg(20)->Arg(40);

// One compensation step: the input that reaches a target from the current memory
// (target: <= 5 us at L = 20; paper 000: 5.4 ms in MATLAB).
void BM_PreisachInverseStep(benchmark::State& state) {
  const int L = static_cast<int>(state.range(0));
  const PreisachModel model = random_model(L, 6);
  const std::vector<double> u = test_like_input(1 << 12, 7);
  const std::vector<double> targets = preisach_targets(model, u);
  PreisachInverter inverter(model);
  PreisachState memory = PreisachState::negative_saturation(model.grid());
  std::size_t i = 0;
  for ([[maybe_unused]] auto _ : state) {
    benchmark::DoNotOptimize(inverter.step(memory, targets[i]).input);
    i = (i + 1) & (targets.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PreisachInverseStep)->Arg(10)->Arg(20)->Arg(40);

// GPI compensation step, 11 operators (target: <= 0.5 us; paper 000: 1.3 ms in MATLAB).
void BM_GpiInverseStep(benchmark::State& state) {
  GpiModel m;
  m.right = {1.100, 0.048};
  m.left = {1.236, 0.088};
  for (int j = 0; j <= 10; ++j) {
    m.radii.push_back(j / 10.0);
    m.weights.push_back(-0.3 * std::exp(-j / 4.0));
  }
  m.bias = 0.396;
  m.v_min = 0.0;
  m.v_max = 5.1;
  std::vector<double> v = test_like_input(1 << 12, 8);
  for (double& x : v) x *= 5.1;
  GpiState plant = GpiState::at_lower_turning_point(m, 0.0), memory = plant;
  std::vector<double> targets;
  targets.reserve(v.size());
  for (double x : v) targets.push_back(gpi_step(m, plant, x));
  GpiInverter inverter(m);
  std::size_t i = 0;
  for ([[maybe_unused]] auto _ : state) {
    benchmark::DoNotOptimize(inverter.step(memory, targets[i]).input);
    i = (i + 1) & (targets.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_GpiInverseStep);

// Paper 001 Algorithm 1 (corrected), for comparison with the exact Preisach inverse.
void BM_IterativeInverseStep(benchmark::State& state) {
  const PreisachModel model = random_model(20, 6);
  const std::vector<double> u = test_like_input(1 << 12, 7);
  const std::vector<double> targets = preisach_targets(model, u);
  PreisachState memory = PreisachState::negative_saturation(model.grid());
  std::size_t i = 0;
  for ([[maybe_unused]] auto _ : state) {
    benchmark::DoNotOptimize(
        iterative_inverse_step(model, memory, targets[i], 0.0, 1.0, 0.05, 1e-9).step.input);
    i = (i + 1) & (targets.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_IterativeInverseStep);

void BM_PreisachIdentification(benchmark::State& state) {
  const int L = static_cast<int>(state.range(0));
  const auto rows = static_cast<std::size_t>(state.range(1));
  const int shifts = static_cast<int>(state.range(2));
  const int threads = static_cast<int>(state.range(3));
  // Readings per hold: each input level read this many times (a data logger sampling through
  // the hold), the same number of rows in all.
  const auto per_hold = static_cast<std::size_t>(state.range(4));
  // kelvin = 1: the model seen through a Kelvin element (c = 0.3, tau three readings), as
  // diagnose's creep extension fits it; the readings of a hold then differ.
  const bool kelvin = state.range(5) != 0;
  const PreisachModel truth = random_model(L, 3);
  std::vector<double> u;
  for (double level : test_like_input(rows / per_hold, 4)) u.insert(u.end(), per_hold, level);
  PreisachState s = PreisachState::negative_saturation(truth.grid());
  Eigen::VectorXd y = truth.simulate(s, u);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1e-3 * y.cwiseAbs().maxCoeff());
  for (Eigen::Index t = 0; t < y.size(); ++t) y[t] += noise(rng);
  // Fixed L and smoothness: no cross-validation. shifts = 1 is one identification (the
  // target); the default fit averages 4 shifted grids, i.e. 4 identifications, which run on
  // `threads` threads (wall time is what a user waits for: UseRealTime).
  PreisachFitOptions opt;
  opt.grid_shifts = shifts;
  opt.threads = threads;
  opt.levels = L;
  opt.smoothness = 0.0;
  opt.lo = 0.0;
  opt.hi = 1.0;
  if (kelvin) {
    opt.output_filter = [](Eigen::Ref<Eigen::VectorXd> p) {
      const double decay = std::exp(-1.0 / 3.0);
      double v = p[0];
      for (Eigen::Index t = 0; t < p.size(); ++t) {
        v = p[t] + (v - p[t]) * decay;
        p[t] = 0.7 * p[t] + 0.3 * v;
      }
    };
  }
  for ([[maybe_unused]] auto _ : state) {
    PreisachFit fit = fit_preisach(u, std::span<const double>(y.data(), u.size()), {}, opt);
    benchmark::DoNotOptimize(fit.model.bias());
  }
}
BENCHMARK(BM_PreisachIdentification)
    ->ArgNames({"L", "rows", "shifts", "threads", "per_hold", "kelvin"})
    ->Args({10, 300, 1, 1, 1, 0})
    ->Args({10, 300, 4, 1, 1, 0})
    ->Args({20, 2000, 1, 1, 1, 0})
    ->Args({40, 20000, 1, 1, 1, 0})
    ->Args({40, 20000, 4, 1, 1, 0})
    ->Args({40, 20000, 4, 2, 1, 0})
    ->Args({40, 20000, 1, 1, 10, 0})
    ->Args({40, 20000, 1, 1, 10, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
