#pragma once
// One fitted single-input model of any family, as a value: the Preisach operator, the GPI
// model, or a polynomial (linear: paper 000's comparison model; poly2: paper 001's). Gives
// the CLI and the augmented model one way to run, invert and store a model whatever its
// family. Rate-independent families carry memory; polynomials do not.
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "scpkit/hysteresis/gpi.hpp"
#include "scpkit/hysteresis/inverse.hpp"
#include "scpkit/hysteresis/lonely.hpp"
#include "scpkit/hysteresis/preisach.hpp"

namespace scpkit {

/// y = c0 + c1 v (+ c2 v^2) on [v_min, v_max] (inputs are clamped there).
struct PolynomialModel {
  std::vector<double> coefficients;  ///< c0, c1[, c2]
  double v_min = 0.0;
  double v_max = 1.0;
  double operator()(double v) const;
  /// The input in [v_min, v_max] giving `target`, nearest to `previous` when two do; the
  /// closest end (reached = false) when none does.
  InverseStep inverse(double target, double previous) const;
};

class HysteresisOperator {
 public:
  using Variant = std::variant<PreisachModel, GpiModel, PolynomialModel, LonelyModel>;
  /// The admissible input range is the model's own (GPI, polynomial: [v_min, v_max];
  /// Preisach: its grid) unless given, as it must be for a Preisach model whose grid extends
  /// beyond the identified inputs.
  explicit HysteresisOperator(Variant model);
  HysteresisOperator(Variant model, double input_min, double input_max);

  /// "preisach", "gpi", "linear", "poly2" or "lonely".
  std::string family() const;
  const Variant& model() const { return model_; }
  double input_min() const;
  double input_max() const;

  /// Runs the inputs; the memory starts (and restarts where `starts` is set, see RestartFlag;
  /// the lonely model also re-arms with the sign of the load change) in the family's
  /// initial state at the lowest admissible input: Preisach negative saturation, GPI the
  /// lower turning point of the major loop at v_min.
  std::vector<double> simulate(std::span<const double> input,
                               std::span<const char> starts = {}) const;

  /// Inputs that track `targets`, the inverse's memory following the plant's (restarting
  /// like simulate(), at the lowest admissible input). Exact wherever reachable.
  std::vector<InverseStep> invert(std::span<const double> targets,
                                  std::span<const char> starts = {}) const;

  /// The same operator with output gain * y + offset (for the augmented model).
  HysteresisOperator with_output_affine(double gain, double offset) const;

 private:
  Variant model_;
  double input_min_, input_max_;
};

}  // namespace scpkit
