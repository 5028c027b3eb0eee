#pragma once
// Thread-to-thread and thread-to-SCP mapping (paper 002 Eqs. 5-8), corrected.
//
// Thread of p plies: eps_thr,p = Gamma_p[F]                                 (Eq. 5)
// q plies share the load, each ply sees F/q:
//   eps_thr,q[F] = Gamma_p[(p/q) F]                    (corrected Eq. 7: input scaling)
// The paper prints Gamma[(q/p)F] = (p/q) Gamma[F]; the two sides disagree, and output
// scaling equals input scaling only for a bias-free, scale-invariant Gamma, which an
// identified Preisach model is not. paper_eq7_as_printed() keeps the printed right-hand side
// for comparison.
//
// SCP made from the thread: eps_SCP,p = g_p eps_thr,p + c_p, g_p = K_thr,p / K_SCP,p   (Eq. 6)
// Hooke at equal load gives eps_SCP,q = (K_SCP,p / K_SCP,q) eps_SCP,p    (corrected Eq. 8;
// the paper prints the ratio upside down). With K_thr,q = (q/p) K_thr,p this is the gain
//   g_q = g_p (q/p) K_SCP,p / K_SCP,q,
// applied to the mapped thread: eps_SCP,q[F] = g_q Gamma_p[(p/q) F] + c_p g_q / g_p. The
// hysteresis is taken at the per-ply load, where the thread was identified; applying the
// equal-load ratio to Gamma_p[F] itself would evaluate Gamma_p outside its identified range
// whenever loads scale with ply count (docs/theory.md).
#include <span>

#include "scpkit/hysteresis/preisach.hpp"
#include "scpkit/mechanics/coil.hpp"

namespace scpkit {

/// eps_thr,q[F] = Gamma_p[(p/q) F]. p, q >= 1.
PreisachModel map_thread_plies(const PreisachModel& thread_p, int p, int q);

/// The paper's printed Eq. 7 right-hand side, (p/q) Gamma_p[F]: a labelled comparison only.
PreisachModel paper_eq7_as_printed(const PreisachModel& thread_p, int p, int q);

/// Least-squares line eps_SCP = gain * eps_thr + offset through paired strains, with R^2.
struct GainFit {
  double gain = 0.0;
  double offset = 0.0;
  double r2 = 0.0;
  int samples = 0;
};
/// Throws IdentificationError for fewer than 3 pairs or a constant thread strain.
GainFit fit_scp_gain(std::span<const double> thread_strain, std::span<const double> scp_strain);

/// g_q = g_p (q/p) K_SCP,p / K_SCP,q with the uncertainty the coil tolerances imply.
Uncertain predict_scp_gain(double g_p, int p, const CoilGeometry& scp_p, int q,
                           const CoilGeometry& scp_q, const CoilTolerances& tol);

/// The gain the paper's printed Eq. 8 implies, g_p (q/p) K_SCP,q / K_SCP,p: comparison only.
double paper_eq8_as_printed_gain(double g_p, int p, const CoilGeometry& scp_p, int q,
                                 const CoilGeometry& scp_q);

/// The q-ply SCP load-to-strain operator: g_q Gamma_p[(p/q) F] + c_p g_q / g_p.
PreisachModel map_thread_to_scp(const PreisachModel& thread_p, int p, const GainFit& gain_p, int q,
                                double gain_q);

}  // namespace scpkit
