#pragma once
// Private to diagnose: the cause named from the detectors' findings and the record's
// model-free signatures (cause.cpp).
#include "scpkit/diagnosis/diagnose.hpp"

namespace scpkit::diagnosis {

struct Context;

/// Sets d.cause and d.cause_note from d.findings (every detector run) and the signatures in
/// ctx: effects read off model-free signatures first (outliers, creep seen in holds,
/// non-congruence), then the lonely stroke and the rest by their held-out gains, compared like
/// for like; with nothing detected, `unexplained` where the held-out error is material where
/// the training identified the memory, else `none`; and last, effects named by their signature
/// alone where their extension gains too little against the noise. May mark a finding detected
/// (by its signature). The lonely stroke's second look (held out within segments) is the
/// caller's: it needs the data.
void name_cause(Context& ctx, Diagnosis& d);

}  // namespace scpkit::diagnosis
