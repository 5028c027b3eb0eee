#pragma once
// Tests at several constant loads (the augmented models' data, PHYSICS.md section 3): whether a
// measurement holds its load over runs of readings, and the load each run is held at. A load
// read back by a load cell scatters about its held value; a load test sweeps it from reading
// to reading.
#include <cstddef>
#include <vector>

#include "scpkit/io/measurement.hpp"

namespace scpkit {

/// Readings per run of one load, on average, from which the load is held in segments (tests at
/// constant loads) rather than swept (load tests). Measured over 1125 voltage test files of the
/// rig and the three independent generators: at least 25; over 759 load test files: at most 4.
inline constexpr std::size_t kReadingsPerHeldLoad = 8;

/// A load read back by a load cell scatters about its held value: a reading within this
/// fraction of the load range of its run's mean so far is in that run. Steps of load tests are
/// 2-8 % of the range (12-50 readings per sweep).
inline constexpr double kHeldLoadTolerance = 0.01;

/// Where each run of one load starts (row indices, the first 0): at each change of the load or
/// of the `segment` column when runs so read are held (kReadingsPerHeldLoad readings each on
/// average), else at each reading farther than kHeldLoadTolerance of the load range from its
/// run's mean so far (or a change of `segment`). Empty when the file has no load column.
std::vector<std::size_t> load_runs(const Measurement& m);

/// True when the load varies and is held over its runs (kReadingsPerHeldLoad): a test at
/// several constant loads. False for a load test (the load swept) or a constant load.
bool load_is_held(const Measurement& m);

/// The load in N with each run (load_runs) read at its mean; a run held exactly keeps its value
/// to the last bit. InputError when the file has no load column.
std::vector<double> held_load_N(const Measurement& m);

}  // namespace scpkit
