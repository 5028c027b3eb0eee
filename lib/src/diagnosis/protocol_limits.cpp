// What a record's protocol keeps diagnose from seeing (docs/diagnose.md, "What it gets wrong"):
// each limit below was measured as a miss on rig and independent-generator data, and each is
// read off the protocol alone, so a test can be checked before it is run.
#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <utility>

#include "scpkit/diagnosis/diagnose.hpp"
#include "scpkit/identification/augmented_fit.hpp"
#include "signatures.hpp"

namespace scpkit {
namespace {

// Whether the segments' loads, in the order tested, strictly rise or strictly fall throughout
// (three or more). adjacent_find, since is_sorted needs a strict order and allows ties.
bool loads_in_order_of_size(const std::vector<double>& seg_load) {
  if (seg_load.size() < 3) return false;
  const auto end = seg_load.end();
  const bool rising = std::adjacent_find(seg_load.begin(), end, std::greater_equal<>()) == end;
  const bool falling = std::adjacent_find(seg_load.begin(), end, std::less_equal<>()) == end;
  return rising || falling;
}

// Each segment's turning values: the inputs where the input turns (holds skipped), in order.
std::vector<std::vector<double>> turning_values(const std::vector<double>& u,
                                                const std::vector<int>& seg, std::size_t segments,
                                                double tol) {
  std::vector<std::vector<double>> out(segments);
  std::vector<int> dir(segments, 0);
  for (std::size_t t = 1; t < u.size(); ++t) {
    if (seg[t] != seg[t - 1] || std::abs(u[t] - u[t - 1]) <= tol) continue;
    const auto s = static_cast<std::size_t>(seg[t]);
    const int d = u[t] > u[t - 1] ? 1 : -1;
    if (dir[s] != 0 && d != dir[s]) out[s].push_back(u[t - 1]);
    dir[s] = d;
  }
  return out;
}

// How many readings return to a memory state met earlier in their segment (memory_states, the
// keys the return-point signatures pair; the last reading of each hold, as their walk takes).
std::size_t returns_to_memory_states(const std::vector<double>& u, const std::vector<int>& seg) {
  const auto [umin, umax] = std::minmax_element(u.begin(), u.end());
  const double tol = 1e-9 * std::max(*umax - *umin, 1e-300);
  const std::vector<std::vector<long>> states = diagnosis::memory_states(u, seg);
  std::set<std::pair<int, std::vector<long>>> met;
  std::size_t returns = 0;
  for (std::size_t t = 0; t < u.size(); ++t) {
    if (t + 1 < u.size() && seg[t + 1] == seg[t] && std::abs(u[t + 1] - u[t]) <= tol) continue;
    if (!met.emplace(seg[t], states[t]).second) ++returns;
  }
  return returns;
}

}  // namespace

std::vector<ProtocolLimit> protocol_limits_of(const DiagnoseData& data) {
  const std::size_t n = data.input.size();
  std::vector<ProtocolLimit> out;
  if (n < 2) return out;
  const auto [umin, umax] = std::minmax_element(data.input.begin(), data.input.end());
  const double span = std::max(*umax - *umin, 1e-300);  // the input's
  std::vector<int> seg(n, 0);
  std::vector<double> seg_load;
  const std::set<double> loads(data.load_N.begin(), data.load_N.end());
  if (!data.input_is_load && data.load_N.size() == n && loads.size() >= 2) {
    for (const LoadSegment& s : split_load_segments(data.load_N, data.segments)) {
      for (std::size_t t = s.first; t < s.first + s.count; ++t)
        seg[t] = static_cast<int>(seg_load.size());
      seg_load.push_back(s.load);
    }
  }

  if (data.input_is_load) {
    out.push_back({"lonely_stroke",
                   "on a load test a first stroke that differs from the later cycles is also a "
                   "virgin specimen's first loading, so it is reported, never named; a test on "
                   "the drive at two or more loads shows it, since it comes back after every "
                   "load change"});
  }

  // Creep with one reading per hold shows only where the holds differ in length: at one
  // length (or one rate along ramps) the lag behind each step is the same function of the
  // memory path in every cycle, loop width to a rate-independent model.
  std::vector<double> time = data.time_s;
  if (time.empty() && !data.dwell_s.empty()) time = reading_times_from_dwell(data);
  if (time.size() == n) {
    const double utol = 1e-9 * span;
    bool read_during_holds = false;
    double shortest = HUGE_VAL, longest = 0.0;
    for (std::size_t t = 1; t < n; ++t) {
      if (seg[t] != seg[t - 1]) continue;
      if (std::abs(data.input[t] - data.input[t - 1]) <= utol) {
        read_during_holds = true;
      } else if (const double dt = time[t] - time[t - 1]; dt > 0.0) {
        shortest = std::min(shortest, dt);
        longest = std::max(longest, dt);
      }
    }
    if (!read_during_holds && !(longest > 1.05 * shortest)) {
      out.push_back({"creep",
                     "with one reading per hold and every hold as long (or readings at one "
                     "rate along ramps), a lag behind each input step looks like loop width, "
                     "which the rate-independent baseline absorbs; vary the hold times or log "
                     "readings during the holds"});
    }
  }

  // A load test whose readings seldom return to a memory state met before (a decaying sine:
  // each branch is traversed once): the baseline's density takes up a slow trend along those
  // branches, and fewer than kFewReturns pairs of readings that a rate-independent model must
  // read alike are too few for the return-point time signature (its regression needs more rows
  // than columns, and then some). Measured (session 75) on the load drifts of the five
  // independent generators' fresh sets (seeds 50000-50011, 80000-80059 of the first two,
  // 96000-96039): with fewer than five returns 15 of 48 were named `drift`, the time signature
  // read on none; with five to nine 20 of 32; with ten or more 259 of 270.
  constexpr std::size_t kFewReturns = 5;
  if (data.input_is_load && returns_to_memory_states(data.input, seg) < kFewReturns) {
    out.push_back({"drift",
                   "fewer than five readings return to a memory state met before (each branch "
                   "is traversed once), so a slow trend in time is taken up by the baseline's "
                   "fit of those branches; return to earlier states later in the test (repeat "
                   "a cycle, or come back to the lowest load between excursions)"});
  }

  // Three loads fix the quadratic maps f1, f2 exactly, whatever the offsets and ranges are,
  // and holding one load out leaves two, which fix only straight lines (baseline.cpp,
  // kLoadsToHoldOutOne): no map beyond quadratic can be fitted or tested.
  const std::set<double> tested(seg_load.begin(), seg_load.end());
  if (tested.size() == 3) {
    out.push_back({"offset_nonlinearity",
                   "three loads fix the quadratic offset and range maps exactly, so a knee or "
                   "any curvature beyond quadratic leaves no residual; test at four or more "
                   "loads (five or more to fit and hold out a map beyond quadratic)"});
  }

  // Two or three loads, each tested once: the maps fit every segment's offset exactly, in
  // any order (measured on rig drifts of 3-12 % at loads 30, 65, 100 g and 100, 40, 70 g: 1
  // of 6 and 1 of 6 named).
  if (tested.size() >= 2 && tested.size() <= 3 && tested.size() == seg_load.size()) {
    out.push_back({"drift",
                   "with each of two or three loads tested once, the offset map fits every "
                   "segment's offset exactly, so a drift over the record shows only inside "
                   "each segment; test at four or more loads in a shuffled order, or test a "
                   "load again later"});
  } else if (loads_in_order_of_size(seg_load)) {
    out.push_back({"drift",
                   "the loads were tested in the order of their size, so a drift over the "
                   "record moves each load's offset as a function of the load, which f1 "
                   "absorbs, and only the drift inside each segment shows; test the loads in "
                   "a shuffled order"});
  }

  // Two or three loads are held out by cycles, so each segment trains the load-shape
  // coupling's operator that predicts its own held-out cycles; where the segments follow
  // protocols of their own, a baseline misfit that differs between them (each protocol meets
  // the grid's cells its own way) looks like a shape changing with the load (measured,
  // session 58: 3 of 29 fresh clean fourth-generator records at three loads, each segment's
  // turning points drawn afresh, named `load_shape_coupling`).
  if (tested.size() >= 2 && tested.size() <= 3) {
    // Steps below 0.1 % of the span are holds; turning values within 1 % of it are one.
    const auto turns = turning_values(data.input, seg, seg_load.size(), 1e-3 * span);
    const auto alike = [span](const std::vector<double>& a, const std::vector<double>& b) {
      return a.size() == b.size() &&
             std::equal(a.begin(), a.end(), b.begin(),
                        [span](double x, double y) { return std::abs(x - y) <= 1e-2 * span; });
    };
    if (!std::all_of(turns.begin(), turns.end(),
                     [&](const std::vector<double>& v) { return alike(v, turns.front()); })) {
      out.push_back({"load_shape_coupling",
                     "with two or three loads, each held out by its own cycles, and a protocol "
                     "of its own in each segment, a misfit of the baseline that differs between "
                     "segments can read as a loop shape changing with the load; run the same "
                     "protocol at every load, or test at four or more loads"});
    }
  }
  return out;
}

}  // namespace scpkit
