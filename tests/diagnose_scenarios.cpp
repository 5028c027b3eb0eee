#include "diagnose_scenarios.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>

namespace scpkit::testing {
namespace {

// A value from a list, picked by a hash of the index and a salt (decorrelates the parameters).
template <typename T, std::size_t N>
T pick(const std::array<T, N>& v, int index, std::uint64_t salt) {
  std::uint64_t x = static_cast<std::uint64_t>(index) * 0x9E3779B97F4A7C15ULL + salt;
  x ^= x >> 31;
  x *= 0xBF58476D1CE4E5B9ULL;
  x ^= x >> 29;
  return v[x % N];
}

}  // namespace

std::string Scenario::describe() const {
  const std::string what =
      effect == "creep"
          ? fmt::format("creep {:g} (tau {:g} s)", magnitude, spec.effects.creep_tau_s)
      : effect == "lonely_stroke" && side == "voltage"
          ? fmt::format(
                "lonely_stroke {:g} ({} after an increase)", magnitude,
                spec.effects.lonely_sign_after_increase > 0.0 ? "same sign" : "opposite sign")
          : fmt::format("{} {:g}", effect, magnitude);
  if (side == "load")
    return fmt::format("load {} seed {} noise {:g} mm, {} x{} spread {:g} per-hold {}{}", what,
                       spec.seed, spec.noise_mm, spec.protocol.shape, spec.protocol.cycles,
                       spec.protocol.dwell_spread, spec.protocol.readings_per_hold,
                       spec.protocol.congruency ? " congruency" : "");
  return fmt::format(
      "voltage {} seed {} noise {:g} mm, loads {} g (in this order), {} truth, "
      "spread {:g} per-hold {}",
      what, spec.seed, spec.noise_mm, fmt::join(spec.voltage.loads_g, " "), spec.voltage.truth,
      spec.voltage.dwell_spread, spec.voltage.readings_per_hold);
}

Scenario make_scenario(const std::string& side, const std::string& effect, int index) {
  Scenario s;
  s.side = side;
  s.effect = effect;
  RigSpec& r = s.spec;
  r.seed = 1000 + static_cast<std::uint64_t>(index) * 7 + std::hash<std::string>{}(effect) % 97;
  r.test = side;
  // Magnitudes from a few times the noise upwards.
  const int level = index % 3;
  auto m = [&](double a, double b, double c) { return level == 0 ? a : level == 1 ? b : c; };
  if (side == "load") {
    r.specimen = "thread";
    r.noise_mm = pick(std::array{0.005, 0.01, 0.02}, index, 1);
    r.protocol.cycles = pick(std::array{6, 8, 10, 12}, index, 2);
    r.protocol.steps_per_half = pick(std::array{6, 8, 10}, index, 3);
    r.protocol.minor_loops = pick(std::array{2, 3, 4}, index, 4);
    r.protocol.dwell_spread = pick(std::array{0.0, 0.5, 1.0}, index, 5);
    r.protocol.shape = pick(std::array<std::string, 2>{"damped", "repeated"}, index, 8);
    r.protocol.readings_per_hold = pick(std::array{1, 1, 3}, index, 9);
    // Loops between the same extrema from different histories: always where the hidden effect
    // needs them to be seen, at random elsewhere (so clean data has them too).
    r.protocol.congruency =
        effect == "minor_loop_noncongruence" || pick(std::array{false, true}, index, 10);
  } else {
    r.specimen = "scp";
    r.length_mm = 70.0;
    r.noise_mm = pick(std::array{0.005, 0.01, 0.02}, index, 1);
    r.voltage.loads_g = pick(std::array{std::vector<double>{30, 40, 50, 60, 70, 80, 90, 100},
                                        std::vector<double>{30, 45, 60, 75, 90, 100},
                                        std::vector<double>{35, 45, 55, 65, 75, 85, 95}},
                             index, 2);
    r.voltage.cycles = pick(std::array{2, 3}, index, 3);
    r.voltage.steps_per_half = pick(std::array{7, 9, 11}, index, 4);
    r.voltage.truth = pick(std::array<std::string, 2>{"gpi", "preisach"}, index, 5);
    r.voltage.dwell_spread = pick(std::array{0.0, 0.5, 1.0}, index, 6);
    r.voltage.readings_per_hold = pick(std::array{1, 1, 3}, index, 9);
    if (pick(std::array{false, true}, index, 8)) {  // loads in a shuffled order
      std::vector<double>& g = r.voltage.loads_g;
      const std::size_t k = static_cast<std::size_t>(index) % g.size();
      std::rotate(g.begin(), g.begin() + static_cast<std::ptrdiff_t>(k), g.end());
      for (std::size_t i = 1; i + 1 < g.size(); i += 3) std::swap(g[i], g[i + 1]);
    }
  }
  RigEffects& e = r.effects;
  if (effect == "drift") e.drift = s.magnitude = m(0.03, 0.06, 0.12);
  if (effect == "outliers") e.outliers = s.magnitude = m(0.1, 0.2, 0.5);
  if (effect == "lonely_stroke") {
    e.lonely_stroke = s.magnitude = m(0.03, 0.06, 0.1);
    // After a load increase: paper 001's opposite sign, or one sign throughout.
    e.lonely_sign_after_increase = pick(std::array{-1.0, 1.0}, index, 11);
  }
  if (effect == "creep") {
    e.creep = s.magnitude = m(0.1, 0.2, 0.4);
    e.creep_tau_s = (side == "load" ? r.protocol.dwell_s : r.voltage.dwell_s) *
                    pick(std::array{0.5, 1.0, 2.0, 5.0}, index, 7);
  }
  if (effect == "minor_loop_noncongruence")
    e.minor_loop_noncongruence = s.magnitude = m(0.4, 0.7, 1.0);
  if (effect == "load_shape_coupling") e.load_shape_coupling = s.magnitude = m(0.3, 0.6, 1.0);
  if (effect == "offset_nonlinearity") e.offset_nonlinearity = s.magnitude = m(0.05, 0.1, 0.2);
  return s;
}

std::string scenario_csv(const Scenario& s) {
  static const Material card = find_material("nylon-110-34-dtex");
  return run_rig(s.spec, card).to_csv();
}

DiagnoseData scenario_data(const Scenario& s) {
  const Measurement m = Measurement::parse(scenario_csv(s), "rig.csv");
  DiagnoseData data;
  data.time_s = m.find(Quantity::kTime)->values;
  data.output = select_response(m).values;
  if (s.side == "voltage") {
    data.input = select_input(m, "voltage_V").values;
    data.input_is_load = false;
    data.load_N = m.find(Quantity::kLoad)->values;
    for (double v : m.find(Quantity::kSegment)->values)
      data.segments.push_back(static_cast<int>(v));
  } else {
    data.input = select_input(m).values;
  }
  return data;
}

Diagnosis diagnose_scenario(const Scenario& s, const DiagnoseOptions& options) {
  const DiagnoseData data = scenario_data(s);
  DiagnoseOptions o = options;
  o.seed = s.spec.seed;
  return diagnose(data, o);
}

}  // namespace scpkit::testing
