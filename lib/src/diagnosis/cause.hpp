#pragma once
// Private to diagnose: the cause named from the detectors' findings and the record's
// model-free signatures (cause.cpp).
#include "scpkit/diagnosis/diagnose.hpp"

namespace scpkit::diagnosis {

struct Context;

/// Creep known by its gain alone is named over a lonely stroke seen at its return points only
/// when it gains this many times as much on held-out data.
inline constexpr double kCreepOverLonely = 1.25;

/// Whether the baseline reproduces every held-out reading within 0.01 % of the range (1 um on a
/// 10 mm stroke, a hundredth of the least error called structure): exact data, on which
/// nothing is named (name_cause) and the lonely stroke's second look is not taken.
bool exact_fit(const Diagnosis& d);

/// Sets d.cause and d.cause_note from d.findings (every detector run) and the signatures in
/// ctx: effects read off model-free signatures first (outliers, creep seen in holds,
/// non-congruence), then the lonely stroke and the rest by their held-out gains, compared like
/// for like; with nothing detected, `unexplained` where the held-out error is material where
/// the training identified the memory, else `none`; and last, effects named by their signature
/// alone where their extension gains too little against the noise. May mark a finding detected
/// (by its signature). The lonely stroke's second look (held out within segments) is the
/// caller's: it needs the data.
void name_cause(Context& ctx, Diagnosis& d);

/// Whether d names creep by the gain of a Kelvin element restarted at each load alone, on a
/// test at several loads driven by voltage whose lonely-stroke offset across loads is
/// significant: the element relaxing from each segment's first reading offsets the first rise
/// as a lonely stroke does, so the caller takes the lonely stroke's second look there too.
bool creep_may_be_lonely_stroke(const Context& ctx, const Diagnosis& d);

}  // namespace scpkit::diagnosis
