#pragma once
// Rig scenarios with one hidden effect, shared by the diagnose tests and the confusion-matrix
// program (tests/diagnose_confusion.cpp). A scenario is drawn from an index: the effect's
// magnitude, the sensor noise, the protocol and the seed all vary with it, so no detector can
// be tuned to one file.
#include <cstdint>
#include <string>
#include <vector>

#include "scpkit/diagnosis/diagnose.hpp"
#include "scpkit/io/measurement.hpp"
#include "scpkit/mechanics/material.hpp"
#include "scpkit/rig/rig.hpp"

namespace scpkit::testing {

struct Scenario {
  std::string side;    ///< "load" (load -> strain of a thread) or "voltage" (several loads)
  std::string effect;  ///< an effect name, or "none"
  double magnitude = 0.0;
  RigSpec spec;
  std::string describe() const;
};

/// Effects the rig can hide on each side.
inline std::vector<std::string> scenario_effects(const std::string& side) {
  if (side == "load")
    return {"none", "lonely_stroke", "creep", "drift", "minor_loop_noncongruence", "outliers"};
  return {"none",    "lonely_stroke",       "creep",
          "drift",   "load_shape_coupling", "offset_nonlinearity",
          "outliers"};
}

/// Scenario number `index` of an effect on a side (deterministic).
Scenario make_scenario(const std::string& side, const std::string& effect, int index);

/// The rig's measurement file (SPEC format) for a scenario.
std::string scenario_csv(const Scenario& s);

/// The rig's file, written and re-read, as `scpkit diagnose` hands it to diagnose().
DiagnoseData scenario_data(const Scenario& s);

/// Runs the rig, writes and re-reads the SPEC file, and diagnoses it as `scpkit diagnose` does.
Diagnosis diagnose_scenario(const Scenario& s, const DiagnoseOptions& options = {});

}  // namespace scpkit::testing
