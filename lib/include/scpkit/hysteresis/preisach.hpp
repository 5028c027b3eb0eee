#pragma once
// Discretised Preisach operator (seed papers 000 Eq. 8, 001 Eq. 1, 002 Eqs. 1-3).
//
//   y(t) = c + integral over P of mu(beta, alpha) * gamma_{beta,alpha}[u](t)
//   P = { (beta, alpha) : lo <= beta <= alpha <= hi }
//
// The plane is cut into L levels of step h = (hi - lo) / L: L(L+1)/2 cells, squares above the
// diagonal and half-squares on it, with mu constant in each cell. The model is parametrised by
// the cell *masses* w_k = integral of mu over cell k, so the regressor of cell k is its signed
// area fraction s_k = (area(+1 part) - area(-1 part)) / area(cell), in [-1, 1], and
//
//   y = c + sum_k w_k s_k                                     (paper 002 Eq. 3, rescaled)
//
// The output is continuous and piecewise quadratic in u, not a staircase.
//
// Memory. The state is the alternating sequence of dominant extrema left after wiping-out,
// s_0 = lo (a minimum), s_1 > s_3 > ... (maxima), s_2 < s_4 < ... (minima), whose last entry is
// the current input. With the Everett function E(a, b) = integral of mu over
// { b <= beta <= alpha <= a } the +1 region's mass is
//
//   mu(+) = sum_{i=1..n} (-1)^(i+1) E(max(s_{i-1}, s_i), min(s_{i-1}, s_i)),
//
// and y = c + 2 mu(+) - mu(P). Each E costs O(1) through prefix sums, so a step costs
// O(memory depth). Parameters (PreisachModel) are an immutable value; the memory
// (PreisachState) is the only thing a step changes.
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace scpkit {

/// The discretisation of the Preisach plane.
struct PreisachGrid {
  double lo = 0.0;  ///< lowest switching threshold (may lie below the physical minimum input)
  double hi = 1.0;  ///< highest switching threshold
  int levels = 10;  ///< L: number of levels per axis

  double step() const { return (hi - lo) / levels; }
  int cells() const { return levels * (levels + 1) / 2; }
  /// Index of cell (i, j): beta in level i, alpha in level j, 0 <= i <= j < L. Row-major over i.
  int cell_index(int i, int j) const { return i * levels - i * (i - 1) / 2 + (j - i); }
  /// Area of cell (i, j) relative to a full square h^2: 1, or 1/2 on the diagonal.
  static double relative_area(int i, int j) { return i == j ? 0.5 : 1.0; }
  /// Throws InvalidArgument unless lo < hi (both finite) and 1 <= levels <= 400.
  void validate() const;
};

/// Memory of a Preisach operator: the dominant turning points (see the header comment).
class PreisachState {
 public:
  /// Negative saturation at grid.lo: every hysteron -1. The default initial state.
  static PreisachState negative_saturation(const PreisachGrid& grid);
  /// Positive saturation: every hysteron +1, input at grid.hi.
  static PreisachState positive_saturation(const PreisachGrid& grid);
  /// A given memory: lo, then alternating dominant maxima and minima, ending with the current
  /// input. Throws InvalidArgument unless the sequence is alternating and dominant.
  static PreisachState from_turning_points(const PreisachGrid& grid, std::vector<double> points);
  /// Negative saturation, then one excursion lo -> hi -> lo (lo < hi inside the grid): a
  /// preconditioned specimen. On a grid reaching below the inputs (lo > grid.lo), the
  /// hysterons below lo are up from the start instead of switching on the first rise, so the
  /// operator has no first-stroke (virgin) term: the conventional plane of PHYSICS.md section 4.
  static PreisachState after_cycle(const PreisachGrid& grid, double lo, double hi);

  /// Back to negative saturation on `grid`, keeping the allocated memory (for loops that
  /// evaluate many designs with one state).
  void reset(const PreisachGrid& grid);

  /// Applies input u (clamped to [lo, hi]) with wiping-out. Allocation-free once the memory
  /// has reached its deepest level so far (capacity is reserved up front).
  void apply(double u);

  double input() const { return points_.back(); }
  /// lo, then the dominant extrema, then the current input.
  std::span<const double> turning_points() const { return points_; }
  int depth() const { return static_cast<int>(points_.size()) - 1; }

 private:
  friend class PreisachModel;
  PreisachState(double lo, double hi);
  void invalidate_from(std::size_t index) {
    if (cache_valid_ > index) cache_valid_ = index;
  }
  double lo_, hi_;
  std::vector<double> points_;
  // Cache of the frozen part of mu(+) (prefix sums of the Everett terms) for the model whose
  // id is cache_owner_: makes a step O(1) amortised. Not part of the memory's value.
  mutable std::vector<double> prefix_;
  mutable std::uint64_t cache_owner_ = 0;
  mutable std::size_t cache_valid_ = 0;
};

/// An identified Preisach operator: grid, cell masses and bias. Immutable.
class PreisachModel {
 public:
  /// weights: one mass per cell, indexed by PreisachGrid::cell_index.
  PreisachModel(PreisachGrid grid, Eigen::VectorXd weights, double bias);

  const PreisachGrid& grid() const { return grid_; }
  const Eigen::VectorXd& weights() const { return weights_; }
  double bias() const { return bias_; }
  /// Density mu in each cell (mass / area), in output units per input unit squared.
  Eigen::VectorXd density() const;

  /// E(a, b): mass of { b <= beta <= alpha <= a }; a and b are clamped to [lo, hi], b <= a.
  double everett(double a, double b) const;
  /// Mass of the whole plane.
  double total_mass() const { return total_; }

  /// Output for a given memory: O(depth) the first time, O(1) amortised when the same state
  /// is stepped with this model (the state caches the frozen part of the sum).
  double output(const PreisachState& state) const;
  /// Applies u to the state and returns the new output.
  double step(PreisachState& state, double u) const {
    state.apply(u);
    return output(state);
  }
  /// Runs a whole input sequence from `state` (updated in place).
  Eigen::VectorXd simulate(PreisachState& state, std::span<const double> input) const;

  /// The same operator read with its input scaled: returns G with G[u] = this[scale * u].
  /// Used by the ply mapping (eps_q[F] = Gamma_p[(p/q) F]). scale > 0.
  PreisachModel with_input_scale(double scale) const;
  /// The same operator with output scaled and shifted: gain * this + offset.
  PreisachModel with_output_affine(double gain, double offset) const;

 private:
  double weight(int i, int j) const { return w_(i, j); }
  PreisachGrid grid_;
  Eigen::VectorXd weights_;
  double bias_;
  std::uint64_t id_ = 0;  // identifies the parameters for the state's cache
  double total_ = 0.0;
  Eigen::MatrixXd w_;       // (L+1) x (L+1), w_(i, j) = mass of cell (i, j), zero elsewhere
  Eigen::MatrixXd node_;    // node_(J, I) = mass of cells with I <= i <= j < J
  Eigen::MatrixXd rowpre_;  // rowpre_(I, j) = sum_{j'=I+1..j} w(I, j')
  Eigen::MatrixXd colpre_;  // colpre_(J, i) = sum_{i'=i..J-1} w(i', J)
};

/// The mean of several Preisach operators, as one operator on a finer grid. Every model's
/// grid nodes must be nodes of `fine` (same step divided by an integer, offsets on the fine
/// node lattice); InvalidArgument otherwise. Exact for inputs inside every model's [lo, hi]:
/// mean_k Gamma_k[u] = Gamma_fine[u] (a sum of Preisach operators is one, with the summed
/// density). Used by the averaged shifted grids of the identification.
PreisachModel average_on_fine_grid(std::span<const PreisachModel> models, const PreisachGrid& fine);

/// Signed area fraction of every cell for a given memory (the identification regressor row),
/// in [-1, 1]; row.size() must equal grid.cells(). O(L^2 + L * depth).
void signed_area_fractions(const PreisachGrid& grid, const PreisachState& state,
                           Eigen::Ref<Eigen::VectorXd> row);

/// Regressor matrix for an input sequence: one row per sample, started from `state`
/// (updated in place).
Eigen::MatrixXd regressor_matrix(const PreisachGrid& grid, PreisachState& state,
                                 std::span<const double> input);

}  // namespace scpkit
