// protocol_limits_of: the effects a record's protocol keeps diagnose from seeing. Over rig
// records of many protocols the limits must be exactly those the rig's own description
// implies (one reading per hold at one hold length: creep; loads in the order of their size:
// drift; a load test: the lonely stroke), read off the data alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "diagnose_scenarios.hpp"
#include "scpkit/diagnosis/diagnose.hpp"

namespace scpkit {
namespace {

std::vector<std::string> effects_of(const std::vector<ProtocolLimit>& limits) {
  std::vector<std::string> out;
  for (const ProtocolLimit& l : limits) {
    EXPECT_FALSE(l.note.empty()) << l.effect;
    out.push_back(l.effect);
  }
  return out;
}

bool sorted_either_way(const std::vector<double>& g) {
  return std::is_sorted(g.begin(), g.end()) || std::is_sorted(g.rbegin(), g.rend());
}

TEST(ProtocolLimits, FollowTheRigsProtocolOverManyScenarios) {
  int creep_hidden = 0, creep_shown = 0, drift_hidden = 0, drift_shown = 0;
  for (const std::string side : {"load", "voltage"}) {
    for (int i = 0; i < 24; ++i) {
      const testing::Scenario s = testing::make_scenario(side, "none", i);
      const std::vector<std::string> got =
          effects_of(protocol_limits_of(testing::scenario_data(s)));
      std::vector<std::string> want;
      if (side == "load") want.push_back("lonely_stroke");
      const int per_hold =
          side == "load" ? s.spec.protocol.readings_per_hold : s.spec.voltage.readings_per_hold;
      const double spread =
          side == "load" ? s.spec.protocol.dwell_spread : s.spec.voltage.dwell_spread;
      const bool creep = per_hold == 1 && spread == 0.0;
      if (creep) want.push_back("creep");
      (creep ? creep_hidden : creep_shown) += 1;
      if (side == "voltage") {
        const bool drift = sorted_either_way(s.spec.voltage.loads_g);
        if (drift) want.push_back("drift");
        (drift ? drift_hidden : drift_shown) += 1;
      }
      EXPECT_EQ(got, want) << side << " scenario " << i;
    }
  }
  // The sample holds both sides of each rule.
  EXPECT_GT(creep_hidden, 0);
  EXPECT_GT(creep_shown, 0);
  EXPECT_GT(drift_hidden, 0);
  EXPECT_GT(drift_shown, 0);
}

// Hand-built records: falling loads hide a drift as rising ones do; two loads in three
// segments are no order; two or three loads each tested once hide a drift across segments,
// three loads a map beyond quadratic, two or three loads with a protocol of their own in each
// segment a coupling's cause; a record without a clock says nothing of creep
// (diagnose does not test creep there and says so).
TEST(ProtocolLimits, LoadOrderClockAndHolds) {
  auto voltage_test = [](const std::vector<double>& loads_N) {
    DiagnoseData d;
    d.input_is_load = false;
    for (double F : loads_N) {
      for (int k = 0; k < 12; ++k) {
        d.input.push_back(k < 6 ? k : 12 - k);
        d.output.push_back(0.0);
        d.load_N.push_back(F);
        d.time_s.push_back(static_cast<double>(d.time_s.size()) * 30.0);
      }
    }
    return d;
  };
  EXPECT_EQ(effects_of(protocol_limits_of(voltage_test({0.3, 0.5, 0.7, 0.9}))),
            (std::vector<std::string>{"creep", "drift"}));
  EXPECT_EQ(effects_of(protocol_limits_of(voltage_test({0.9, 0.7, 0.5, 0.3}))),
            (std::vector<std::string>{"creep", "drift"}));
  EXPECT_EQ(effects_of(protocol_limits_of(voltage_test({0.5, 0.9, 0.3, 0.7}))),
            (std::vector<std::string>{"creep"}));
  EXPECT_EQ(effects_of(protocol_limits_of(voltage_test({0.3, 0.9, 0.3}))),
            (std::vector<std::string>{"creep"}));
  // Three loads fix the quadratic maps, in any order and with one of them tested twice; two or
  // three loads each tested once fix every segment's offset, in any order.
  EXPECT_EQ(effects_of(protocol_limits_of(voltage_test({0.3, 0.9, 0.5}))),
            (std::vector<std::string>{"creep", "offset_nonlinearity", "drift"}));
  EXPECT_EQ(effects_of(protocol_limits_of(voltage_test({0.3, 0.5, 0.9}))),
            (std::vector<std::string>{"creep", "offset_nonlinearity", "drift"}));
  EXPECT_EQ(effects_of(protocol_limits_of(voltage_test({0.3, 0.9, 0.5, 0.3}))),
            (std::vector<std::string>{"creep", "offset_nonlinearity"}));
  EXPECT_EQ(effects_of(protocol_limits_of(voltage_test({0.9, 0.3}))),
            (std::vector<std::string>{"creep", "drift"}));

  DiagnoseData varied = voltage_test({0.5, 0.9, 0.3, 0.7});
  for (std::size_t t = 1; t < varied.time_s.size(); ++t)
    varied.time_s[t] = varied.time_s[t - 1] + (t % 3 == 0 ? 60.0 : 30.0);
  EXPECT_TRUE(protocol_limits_of(varied).empty());

  DiagnoseData held = voltage_test({0.5, 0.9, 0.3, 0.7});
  held.input[5] = held.input[4];  // two readings in one hold
  EXPECT_TRUE(protocol_limits_of(held).empty());

  // Two or three loads (held out by cycles) whose segments follow protocols of their own: a
  // misfit that differs between segments can read as a coupling. Not where every segment
  // turns at the same inputs, nor at four loads (held out by load).
  auto own_protocols = [&](const std::vector<double>& loads_N) {
    DiagnoseData d = voltage_test(loads_N);
    for (std::size_t t = 12; t < 24; ++t) d.input[t] *= 0.5;  // the second segment turns at 3
    return d;
  };
  EXPECT_EQ(
      effects_of(protocol_limits_of(own_protocols({0.3, 0.9, 0.5}))),
      (std::vector<std::string>{"creep", "offset_nonlinearity", "drift", "load_shape_coupling"}));
  EXPECT_EQ(effects_of(protocol_limits_of(own_protocols({0.9, 0.3}))),
            (std::vector<std::string>{"creep", "drift", "load_shape_coupling"}));
  EXPECT_EQ(effects_of(protocol_limits_of(own_protocols({0.5, 0.9, 0.3, 0.7}))),
            (std::vector<std::string>{"creep"}));

  DiagnoseData unclocked = voltage_test({0.3, 0.5, 0.7, 0.9});
  unclocked.time_s.clear();
  EXPECT_EQ(effects_of(protocol_limits_of(unclocked)), (std::vector<std::string>{"drift"}));
}

// A load test that seldom returns to a memory state met before hides a drift: the return-point
// time signature needs five such returns. Excursions 0 -> top -> 0 to distinct tops return once
// per excursion after the first (back at the lowest load, every hysteron off); the readings at
// the tops are each a state of their own. Four excursions hide a drift, five do not; a decaying
// sine, each turning value met once, hides it; the same sine read through repeated cycles
// between fixed extrema does not. Readings at varied intervals, so the clock hides no creep.
TEST(ProtocolLimits, ALoadTestThatSeldomReturnsToAMemoryStateHidesADrift) {
  auto load_test = [](const std::vector<double>& u) {
    DiagnoseData d;
    d.input_is_load = true;
    for (std::size_t t = 0; t < u.size(); ++t) {
      d.input.push_back(u[t]);
      d.output.push_back(u[t]);
      d.time_s.push_back(t == 0 ? 0.0 : d.time_s.back() + (t % 3 == 0 ? 20.0 : 10.0));
    }
    return d;
  };
  auto excursions = [](int k) {
    std::vector<double> u{0.0};
    for (int e = 0; e < k; ++e) {
      u.push_back(0.5 + 0.1 * e);
      u.push_back(0.0);
    }
    return u;
  };
  const std::vector<std::string> hidden{"lonely_stroke", "drift"}, shown{"lonely_stroke"};
  EXPECT_EQ(effects_of(protocol_limits_of(load_test(excursions(4)))), hidden);
  EXPECT_EQ(effects_of(protocol_limits_of(load_test(excursions(5)))), shown);
  // Holds do not count as returns: every reading of the four excursions read three times.
  std::vector<double> held;
  for (double v : excursions(4)) held.insert(held.end(), {v, v, v});
  EXPECT_EQ(effects_of(protocol_limits_of(load_test(held))), hidden);

  std::vector<double> sine, cycles;
  for (int k = 0; k < 150; ++k) {
    sine.push_back(0.5 + 0.45 * std::exp(-k / 60.0) * std::sin(2.0 * std::numbers::pi * k / 30.0));
    cycles.push_back(0.5 + 0.45 * std::sin(2.0 * std::numbers::pi * k / 30.0));
  }
  EXPECT_EQ(effects_of(protocol_limits_of(load_test(sine))), hidden);
  EXPECT_EQ(effects_of(protocol_limits_of(load_test(cycles))), shown);
}

}  // namespace
}  // namespace scpkit
