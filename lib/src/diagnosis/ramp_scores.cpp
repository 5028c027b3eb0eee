// Spikes that break a monotone branch, judged on the readings alone (load tests): the
// model-free scores the outliers detector (outliers.cpp) takes beside its residual-based tiers.
// Along a ramp of the input a rate-independent response with a non-negative density moves one
// way, smoothly where the readings are close; a spike breaks that whatever model is fitted.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "detectors.hpp"
#include "stats.hpp"

namespace scpkit::diagnosis {
namespace {

/// A pass of a record: readings first..last of one segment along which the input moves one way
/// (`way`, +1 up), as long as it keeps moving that way.
struct Pass {
  std::size_t first, last;
  double way;
};

/// The record's passes; consecutive passes share their turning reading.
std::vector<Pass> passes(const Record& rec) {
  std::vector<Pass> out;
  for (std::size_t s = 0; s + 1 < rec.size();) {
    const double way = rec.u[s + 1] > rec.u[s] ? 1.0 : rec.u[s + 1] < rec.u[s] ? -1.0 : 0.0;
    if (way == 0.0 || rec.seg[s + 1] != rec.seg[s]) {
      ++s;
      continue;
    }
    std::size_t e = s + 1;
    while (e + 1 < rec.size() && rec.seg[e + 1] == rec.seg[e] &&
           (rec.u[e + 1] - rec.u[e]) * way > 0.0)
      ++e;
    out.push_back({s, e, way});
    s = e;
  }
  return out;
}

/// How far the two steps at a turning value of the input (reading t, both neighbours on one
/// side of it, `turn` +1 at a top) exceed, the smaller of the two, the largest change of the
/// response over the same input interval, in the same direction, on every other pass of the
/// record; 0 where no other pass spans an interval. `sign`: +1 where the response rises with
/// the input. A spike at a turning value in the direction of the turn keeps the reading the
/// response's extreme among its neighbours (the monotonicity test in ramp_scores passes it)
/// but lengthens both steps by its size. Rate-independent memory does not: the step out of a
/// turning value starts a branch, and on a Preisach plane of non-negative density the change
/// from a reversal at a to b is the density over the triangle a <= beta <= alpha <= b, the
/// least of every branch's change over [a, b], while the step in ends a branch that other
/// passes from the same or further reversals repeat. A lag behind each step (creep read once
/// per hold) shortens both steps, a drift adds its per-step trend to every pass alike.
double turn_steps_excess(const Record& rec, const std::vector<Pass>& all, std::size_t t,
                         double turn, double sign) {
  // The largest change of sign * y from input lo to hi along another pass moving `way`:
  // positive along either way for a response that rises with the input.
  auto largest_other = [&](double lo, double hi, double way) {
    double largest = -HUGE_VAL;
    for (const Pass& p : all) {
      const std::size_t s = p.first, e = p.last;
      if (p.way != way || (s <= t && t <= e) || std::min(rec.u[s], rec.u[e]) > lo ||
          std::max(rec.u[s], rec.u[e]) < hi)
        continue;
      auto at = [&](double v) {  // sign * y interpolated along the pass at input v
        for (std::size_t k = s; k < e; ++k) {
          const double u0 = rec.u[k], u1 = rec.u[k + 1];
          if ((v - u0) * (v - u1) > 0.0) continue;
          const double w = (v - u0) / (u1 - u0);
          return sign * ((1.0 - w) * rec.y[k] + w * rec.y[k + 1]);
        }
        return sign * rec.y[e];
      };
      largest = std::max(largest, at(hi) - at(lo));
    }
    return largest;
  };
  const double a = rec.u[t - 1], b = rec.u[t], c = rec.u[t + 1];
  // Both steps in the same frame: the change of sign * y from the lower input to the higher.
  const double in = turn * sign * (rec.y[t] - rec.y[t - 1]);
  const double out = turn * sign * (rec.y[t] - rec.y[t + 1]);
  const double in_other = largest_other(std::min(a, b), std::max(a, b), turn);
  const double out_other = largest_other(std::min(b, c), std::max(b, c), -turn);
  if (!std::isfinite(in_other) || !std::isfinite(out_other)) return 0.0;
  return std::max(0.0, std::min(in - in_other, out - out_other));
}

/// A spike smaller than its ramp's step (session 74): inside the interval of its neighbours,
/// so that it breaks no monotone branch, but off their interpolation (`e`, NaN off the ramps;
/// `w[k]`: the weight of reading k + 1 in e[k]). Moving reading t by s moves e[t] by s and its
/// neighbours' e by -w s each, w their interpolation weights of t; a kink of the branch or a
/// relay's step between two readings moves one or two of them, a curvature all three alike, as
/// it moves e[t - 2] and e[t + 2], which the spike does not: the three are taken off the mean of
/// those two (`d`). Scored by the least of the three estimates of s, d[t] and the neighbours' d
/// over their weights, where the neighbours lie the other way (nothing within two sensor steps),
/// in units of the MAD of d over the other readings in the middle of seven along a ramp (at
/// least half a sensor step and 1e-4 of `range`); the others are those outside the reading's
/// footprint (the spike moves d from t - 2 to t + 2), six at least; the reading must carry the
/// largest amplitude in its footprint (a spike at t - 1 enters the mean d is taken off at t + 1,
/// and made the pattern there on a rig record read at a 0.04 mm step). And only where the
/// least-squares amplitude of the pattern stands more than kPattern scales off the others' (the
/// RMS of their amplitudes without the largest tenth, over 0.79, that RMS's ratio to sigma for a
/// normal, which below ten others drop none and overstate it): a response read coarsely on a relay
/// grid steps between readings by differing amounts and makes the pattern at many readings, a spike
/// at one. Measured on 9 180 load records of the five independent generators without spikes (7 000
/// clean, 1 500 non-congruences, the rest creeps, noise-free ones among them, and drifts): the
/// tier raised the largest ramp score of 230, to 5.5 at most (a noise-free fifth-generator
/// creep; 5.0 on a clean record); it lifted 20 of 360 spiked records above the outliers tier's
/// kRamp, 4 of them named `none` before (spikes of 5-15 % of the range, read at 12-30 points per
/// ramp: the third generator's fresh 50001 at 12.6, the fourth's 50007 at 11.9).
std::vector<double> inside_ramp_scores(const std::vector<double>& e, const std::vector<double>& w,
                                       double resolution, double range) {
  constexpr double kPattern = 4.0, kNormalRatio = 0.79;
  constexpr std::size_t kFewest = 6;
  const std::size_t n = e.size();
  std::vector<std::size_t> at;  // the readings in the middle of five interpolations
  std::vector<double> least, d, amplitude;
  std::vector<double> out(n, 0.0);
  for (std::size_t t = 2; t + 2 < n; ++t) {
    bool ramp = true;
    for (std::size_t k = t - 2; k <= t + 2; ++k) ramp = ramp && !std::isnan(e[k]);
    if (!ramp) continue;
    const double curve = 0.5 * (e[t - 2] + e[t + 2]);
    const double d0 = e[t] - curve, dl = e[t - 1] - curve, dr = e[t + 1] - curve;
    const double wl = w[t - 1], wr = 1.0 - w[t + 1];
    at.push_back(t);
    d.push_back(d0);
    amplitude.push_back((d0 - wl * dl - wr * dr) / (1.0 + wl * wl + wr * wr));
    const bool pattern = d0 * dl < 0.0 && d0 * dr < 0.0 && std::abs(d0) > 2.0 * resolution;
    least.push_back(pattern ? std::min({std::abs(d0), std::abs(dl) / wl, std::abs(dr) / wr}) : 0.0);
  }
  for (std::size_t i = 0; i < at.size(); ++i) {
    if (least[i] == 0.0) continue;
    // The record's own, outside the reading's footprint (the spike moves d and the amplitude
    // from t - 2 to t + 2); and the footprint's largest amplitude, which is the spike's: a
    // spike at t - 1 enters the mean d is taken off at t + 1 and can make the pattern there.
    std::vector<double> others, sq;
    bool largest = true;
    for (std::size_t j = 0; j < at.size(); ++j) {
      if (at[j] + 2 >= at[i] && at[j] <= at[i] + 2) {
        largest = largest && std::abs(amplitude[j]) <= std::abs(amplitude[i]);
        continue;
      }
      others.push_back(d[j]);
      sq.push_back(amplitude[j] * amplitude[j]);
    }
    if (!largest || sq.size() < kFewest) continue;
    const double own = trimmed_sigma(sq, 10, kNormalRatio);
    const double scale = std::max({mad(others), 0.5 * resolution, 1e-4 * range});
    if (std::abs(amplitude[i]) > kPattern * own) out[at[i]] = least[i] / scale;
  }
  return out;
}

}  // namespace

/// Spikes on a ramp (session 26): where the input moves strictly one way through readings
/// t - 1, t, t + 1 (one segment), a rate-independent response with a non-negative density
/// moves one way too, and smoothly where the readings are close. Reading t's score: the lesser
/// of its distance from the interpolation between its neighbours at its input (off the median
/// of those distances) and how far it lies outside the interval of its neighbours (how far it
/// breaks the branch's monotonicity), in units of the MAD of those distances (at least half a
/// sensor step and 1e-4 of the range); 0 within two sensor steps of that interval. The MAD is
/// the smaller of the one over every ramp reading and the one over the half whose neighbours
/// lie closest together: where the neighbours are far apart, the response's curvature between
/// them (or the steps of a coarse relay grid) moves the interpolation by more than the noise
/// does, and does not move a reading outside the interval (measured, session 62, on clean
/// records: on the fifth independent generator's 24-level relay grids the MAD over every ramp
/// reading was 1.5-4.5 times the sensor noise, the smaller of the two 0.9-2.8 times; on the
/// third 0.7-2.1 and 0.6-2.1 times). A transformation steeper than the reading step puts a
/// reading far off the interpolation but inside the interval, or outside it by the noise only
/// (measured: Preisach planes with ridges 0.05-0.09 V wide read every 0.1 V, a reading at the
/// knee of a fall 0.005 above its flat neighbour and half the fall off the interpolation:
/// 11-125 MADs by the distance alone).
/// Needs no model, so no misfit of a coarse baseline on a short record hides a spike.
/// Since session 62 also, scored by how far they break monotonicity alone: a reading at a
/// turning value of the input that is not the response's extreme among its neighbours (its
/// highest at a top, where the response rises with the input, the record's direction along its
/// ramps), and a run of two or three readings inside a ramp, each outside the interval of the
/// readings either side of the run (a spike at a turning value, or two in a row, passed the
/// single-reading test: measured on fresh fifth- and third-generator records, 8-17 noise
/// sigmas, named `none`; the largest such score on 650 load records without spikes 2.9).
/// Since session 64 also a reading at a turning value whose two steps exceed every other
/// pass's change over their inputs (turn_steps_excess).
std::vector<double> ramp_scores(const Record& rec, double resolution) {
  const std::size_t n = rec.size();
  std::vector<double> out(n, 0.0), e(n, std::numeric_limits<double>::quiet_NaN()), all;
  std::vector<double> w(n, 0.0);                             // the weight of reading t + 1 in e[t]
  std::vector<std::pair<double, double>> by_gap;             // (neighbours' distance, e)
  auto one_segment = [&rec](std::size_t a, std::size_t b) {  // readings a..b
    for (std::size_t t = a; t < b; ++t) {
      if (rec.seg[t] != rec.seg[t + 1]) return false;
    }
    return true;
  };
  // The response's direction along the input over the ramps (positive: it rises with it).
  double direction = 0.0;
  for (std::size_t t = 1; t + 1 < n; ++t) {
    if (!one_segment(t - 1, t + 1)) continue;
    const double a = rec.u[t - 1], b = rec.u[t], c = rec.u[t + 1];
    if (!((a < b && b < c) || (a > b && b > c))) continue;
    w[t] = (b - a) / (c - a);
    e[t] = rec.y[t] - ((1.0 - w[t]) * rec.y[t - 1] + w[t] * rec.y[t + 1]);
    all.push_back(e[t]);
    by_gap.emplace_back(std::abs(rec.y[t + 1] - rec.y[t - 1]), e[t]);
    direction += (rec.y[t + 1] - rec.y[t - 1]) * (c - a);
  }
  if (all.size() < 20) return out;
  const double m = median(all);
  std::sort(by_gap.begin(), by_gap.end());
  std::vector<double> close;
  for (std::size_t i = 0; i < by_gap.size() / 2; ++i) close.push_back(by_gap[i].second);
  const double scale =
      std::max({std::min(mad(all), mad(close)), 0.5 * resolution, 1e-4 * rec.range});
  for (std::size_t t = 1; t + 1 < n; ++t) {
    if (std::isnan(e[t])) continue;
    const double lo = std::min(rec.y[t - 1], rec.y[t + 1]),
                 hi = std::max(rec.y[t - 1], rec.y[t + 1]);
    const double outside = std::max(lo - rec.y[t], rec.y[t] - hi);
    if (outside > 2.0 * resolution) out[t] = std::min(std::abs(e[t] - m), outside) / scale;
  }
  // Two more ways a monotone response is broken, scored by how far it is broken.
  auto mark = [&](std::size_t t, double outside) {
    if (outside > 2.0 * resolution) out[t] = std::max(out[t], outside / scale);
  };
  // At a turning value of the input (both neighbours on one side of it) the response is at an
  // extreme among its neighbours: its highest where the input is, if it rises with the input.
  // And its two steps are no longer than other passes make them (turn_steps_excess).
  const std::vector<Pass> record_passes = passes(rec);
  for (std::size_t t = 1; t + 1 < n; ++t) {
    const double a = rec.u[t - 1], b = rec.u[t], c = rec.u[t + 1];
    const double turn = b > a && b > c ? 1.0 : b < a && b < c ? -1.0 : 0.0;
    if (turn == 0.0 || !one_segment(t - 1, t + 1)) continue;
    const double y0 = rec.y[t - 1], y1 = rec.y[t], y2 = rec.y[t + 1];
    mark(t, turn * direction >= 0.0 ? std::max(y0, y2) - y1 : y1 - std::min(y0, y2));
    mark(t, turn_steps_excess(rec, record_passes, t, turn, direction >= 0.0 ? 1.0 : -1.0));
  }
  // A run of two or three readings inside a ramp (the input moving strictly one way from the
  // reading before the run to the one after it): each lies in the interval of the readings
  // either side of the run. The run scores its reading least outside it.
  constexpr std::size_t kRun = 3;
  for (std::size_t len = 2; len <= kRun; ++len) {
    for (std::size_t t = 1; t + len < n; ++t) {
      const std::size_t last = t + len;  // the reading after the run
      if (!one_segment(t - 1, last)) continue;
      bool ramp = true;
      for (std::size_t s = t - 1; s < last; ++s) {
        ramp = ramp && (rec.u[s + 1] - rec.u[s]) * (rec.u[t] - rec.u[t - 1]) > 0.0;
      }
      if (!ramp) continue;
      const double lo = std::min(rec.y[t - 1], rec.y[last]),
                   hi = std::max(rec.y[t - 1], rec.y[last]);
      double least = HUGE_VAL;
      for (std::size_t s = t; s < last; ++s)
        least = std::min(least, std::max(lo - rec.y[s], rec.y[s] - hi));
      for (std::size_t s = t; s < last; ++s) mark(s, least);
    }
  }
  // A spike inside the interval of its neighbours (inside_ramp_scores).
  const std::vector<double> inside = inside_ramp_scores(e, w, resolution, rec.range);
  for (std::size_t t = 0; t < n; ++t) out[t] = std::max(out[t], inside[t]);
  return out;
}

}  // namespace scpkit::diagnosis
