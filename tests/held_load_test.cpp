// Where a measurement holds its load (tests at several constant loads) and the load each run of
// readings is held at: exact runs unchanged to the bit, a load cell's scatter averaged per run,
// a swept load (a load test) not held. Sampled over random loads, run lengths and scatter.
#include "scpkit/io/held_load.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "scpkit/error.hpp"
#include "scpkit/io/measurement.hpp"

namespace scpkit {
namespace {

// A voltage test: `loads` (g) held `per_run` readings each, plus `scatter` (g, Gaussian) on
// every reading; with `segments`, a segment column numbering the runs.
struct HeldTest {
  std::string text;
  std::vector<std::size_t> starts;     // the true run starts
  std::vector<std::vector<double>> g;  // each run's readings as written (g)
};

HeldTest voltage_test(const std::vector<double>& loads, std::size_t per_run, double scatter,
                      bool segments, std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, scatter);
  HeldTest t;
  t.text = segments ? "segment,load_g,voltage_V,disp_mm\n" : "load_g,voltage_V,disp_mm\n";
  std::size_t row = 0;
  for (std::size_t s = 0; s < loads.size(); ++s) {
    t.starts.push_back(row);
    t.g.emplace_back();
    for (std::size_t i = 0; i < per_run; ++i, ++row) {
      // Written as a file writes it (6 decimals), so the expected means use the same values.
      const double g = std::round((loads[s] + (scatter > 0.0 ? noise(rng) : 0.0)) * 1e6) / 1e6;
      t.g.back().push_back(g);
      char line[128];
      std::snprintf(line, sizeof line, "%.6f,%.3f,%.4f\n", g, 0.5 * static_cast<double>(i % 9),
                    0.01 * static_cast<double>(i));
      t.text += (segments ? std::to_string(s) + "," : std::string()) + line;
    }
  }
  return t;
}

std::vector<double> random_loads(std::mt19937& rng) {
  std::uniform_int_distribution<int> count(2, 8), tens(2, 20);
  std::vector<double> loads(static_cast<std::size_t>(count(rng)));
  for (double& l : loads) l = 10.0 * tens(rng);
  // Neighbouring runs at one load are one run unless a segment column parts them.
  for (std::size_t i = 1; i < loads.size(); ++i) {
    if (loads[i] == loads[i - 1]) loads[i] += 5.0;
  }
  loads.push_back(250.0);  // a range of at least 45 g: the scatter is under 1 % of it
  return loads;
}

TEST(HeldLoad, ExactRunsAreKeptToTheBit) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 40; ++trial) {
    const std::vector<double> loads = random_loads(rng);
    const std::size_t per_run = kReadingsPerHeldLoad + static_cast<std::size_t>(trial % 30);
    const HeldTest t = voltage_test(loads, per_run, 0.0, trial % 2 == 0, rng);
    const Measurement m = Measurement::parse(t.text, "v.csv");
    EXPECT_TRUE(load_is_held(m));
    EXPECT_EQ(load_runs(m), t.starts);
    const std::vector<double> held = held_load_N(m);
    ASSERT_EQ(held.size(), m.rows());
    for (std::size_t r = 0; r < held.size(); ++r)
      EXPECT_EQ(held[r], m.find(Quantity::kLoad)->values[r]);  // bitwise, not near
  }
}

TEST(HeldLoad, ALoadCellsScatterIsAveragedOverEachRun) {
  std::mt19937 rng(12);
  for (int trial = 0; trial < 40; ++trial) {
    const std::vector<double> loads = random_loads(rng);
    const HeldTest t = voltage_test(loads, 25, 0.1, false, rng);
    const Measurement m = Measurement::parse(t.text, "v.csv");
    EXPECT_TRUE(load_is_held(m));
    EXPECT_EQ(load_runs(m), t.starts);
    const std::vector<double> held = held_load_N(m);
    for (std::size_t s = 0; s < t.g.size(); ++s) {
      // Each run at the mean of its readings, recomputed here from the written grams.
      const double mean_N = std::accumulate(t.g[s].begin(), t.g[s].end(), 0.0) /
                            static_cast<double>(t.g[s].size()) * 9.80665e-3;
      for (std::size_t i = 0; i < t.g[s].size(); ++i)
        EXPECT_NEAR(held[t.starts[s] + i], mean_N, 1e-12);
    }
  }
}

TEST(HeldLoad, ASegmentColumnStartsARunAtAnEqualLoad) {
  std::mt19937 rng(13);
  const HeldTest t = voltage_test({50.0, 50.0, 80.0}, 10, 0.0, true, rng);
  const Measurement m = Measurement::parse(t.text, "v.csv");
  EXPECT_EQ(load_runs(m), (std::vector<std::size_t>{0, 10, 20}));
}

TEST(HeldLoad, ASweptOrConstantLoadIsNotHeld) {
  std::mt19937 rng(14);
  std::uniform_int_distribution<int> steps(6, 25);
  for (int trial = 0; trial < 20; ++trial) {
    // A load test: up and down in steps, one to four readings per step.
    const int n = steps(rng), per = 1 + trial % 4;
    std::string text = "load_g,disp_mm\n";
    for (int cycle = 0; cycle < 3; ++cycle) {
      for (int k = 0; k <= 2 * n; ++k) {
        const int level = k <= n ? k : 2 * n - k;
        for (int r = 0; r < per; ++r)
          text += std::to_string(20 * level) + "," + std::to_string(0.01 * level) + "\n";
      }
    }
    EXPECT_FALSE(load_is_held(Measurement::parse(text, "l.csv"))) << text.substr(0, 60);
  }
  EXPECT_FALSE(
      load_is_held(Measurement::parse("load_g,voltage_V,disp_mm\n50,0,0\n50,1,1\n", "c.csv")));
}

TEST(HeldLoad, WithoutALoadColumnTheHeldLoadIsAnError) {
  const Measurement m = Measurement::parse("voltage_V,disp_mm\n0,0\n1,1\n", "n.csv");
  EXPECT_TRUE(load_runs(m).empty());
  EXPECT_FALSE(load_is_held(m));
  EXPECT_THROW(held_load_N(m), InputError);
  EXPECT_FALSE(column_varies(nullptr));
}

}  // namespace
}  // namespace scpkit
