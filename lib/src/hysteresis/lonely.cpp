#include "scpkit/hysteresis/lonely.hpp"

#include <algorithm>

#include "scpkit/error.hpp"

namespace scpkit {

void LonelyModel::validate() const {
  if (static_cast<int>(column_weights.size()) != preisach.grid().levels) {
    throw_invalid("lonely model needs one column weight per level ({}), got {}",
                  preisach.grid().levels, column_weights.size());
  }
}

double LonelyModel::running_max_term(double M) const {
  const PreisachGrid& g = preisach.grid();
  const double h = g.step();
  double s = 0.0;
  for (int j = 0; j < g.levels; ++j) {
    s += column_weights[j] * (2.0 * std::clamp((M - (g.lo + j * h)) / h, 0.0, 1.0) - 1.0);
  }
  return s;
}

LonelyState LonelyState::initial(const LonelyModel& m, char flag) {
  LonelyState s{PreisachState::negative_saturation(m.preisach.grid()), m.preisach.grid().lo,
                flag == kRestartAfterLoadIncrease ? -1.0 : 1.0};
  return s;
}

double lonely_output(const LonelyModel& m, const LonelyState& s) {
  return m.preisach.output(s.preisach) + s.sigma * m.running_max_term(s.running_max);
}

double lonely_step(const LonelyModel& m, LonelyState& s, double u) {
  s.preisach.apply(u);
  s.running_max = std::max(s.running_max, s.preisach.input());
  return lonely_output(m, s);
}

}  // namespace scpkit
