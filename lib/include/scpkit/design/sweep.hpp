#pragma once
// Batch design sweeps: a grid and/or seeded random samples over ply counts and coil geometry,
// constraints, an objective to rank by, one CSV row per candidate with every figure and the
// reason a candidate is infeasible.
//
// Determinism: candidate i is a pure function of (spec, i) (grid by mixed radix, random samples
// from a counter-based generator seeded with (seed, i)), each row is formatted by one function,
// and the ranking key is read back from the row's own text. So the output is byte-identical for
// any thread count, and shards (candidates with i mod N = k) merge into exactly the unsharded
// result (docs/design.md).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "scpkit/design/design.hpp"
#include "scpkit/io/measurement.hpp"

namespace scpkit {

/// Values of one design variable: a list (or from/to/steps grid) for the grid, and its span
/// for random samples.
struct SweepAxis {
  std::vector<double> values;
  double min() const;
  double max() const;
};

struct SweepSpec {
  std::filesystem::path thread_model;   ///< paired thread/SCP model (scpkit fit)
  std::filesystem::path voltage_model;  ///< optional augmented voltage model
  std::string material;                 ///< card id; default: the thread model's
  std::uint64_t seed = 1;
  long long random_samples = 0;
  bool grid = true;  ///< include the full grid

  std::vector<int> plies{2};
  std::optional<SweepAxis> wire_d_mm;  ///< default: from the card per ply count
  SweepAxis spring_index{{1.5}};       ///< D / d (mean diameter)
  SweepAxis coils{{300}};
  std::vector<int> legs{2};
  SweepAxis length_mm{{100}};

  double load_min_g = 20, load_max_g = 250;
  int protocol_steps = 100;
  double working_load_g = 0, target_stroke_mm = 0;

  // Constraints (0 or negative = off).
  double min_stroke_mm = 0, max_hysteresis_pct = 0, max_stiffness_N_per_m = 0,
         min_thermal_stroke_mm = 0;
  double max_voltage_V = 0;
  double max_strain_pct = 50;  ///< physical limit (design.hpp); always applied

  std::string objective = "stroke_mm";  ///< a numeric column of the output
  bool maximize = true;
  CoilTolerances tolerances;

  std::size_t grid_count() const;
  std::size_t candidate_count() const;
};

/// Reads a sweep description (TOML; paths relative to the file). InputError with line/column.
SweepSpec load_sweep_spec(const std::filesystem::path& path);

struct SweepContext {
  SweepSpec spec;
  ThreadCharacterisation characterisation;
  Material material;
};

/// Loads the models and the material a spec names.
SweepContext prepare_sweep(const SweepSpec& spec);

/// The design for candidate i.
DesignSpec sweep_candidate(const SweepContext& ctx, std::size_t index);

/// The CSV header (no newline) and one row (no newline) for an evaluated candidate.
std::string sweep_header();
std::string sweep_row(const SweepContext& ctx, std::size_t index, const DesignSpec& d,
                      const DesignResult& r);

/// Evaluates the candidates of shard k of n (i mod n == k) with `threads` threads; rows come back
/// in candidate order. `progress(done, total)` is called from worker threads now and then.
std::vector<std::string> run_sweep(
    const SweepContext& ctx, int shard, int shards, int threads,
    const std::function<void(std::size_t, std::size_t)>& progress = {});

/// Ranks rows: feasible first, then by the objective column, then by candidate index.
void rank_rows(std::vector<std::string>& rows, const std::string& objective, bool maximize);

/// A whole output file: a comment line naming the sweep, the header, the ranked rows.
std::string sweep_file(const SweepSpec& spec, const std::string& spec_name,
                       std::vector<std::string> rows, int shard = 0, int shards = 1);

/// One design file (`scpkit design`, docs/design.md): the characterisation it names, the
/// design, and the load protocol file when it gives one. InputError with line and column.
struct DesignFile {
  SweepContext context;
  DesignSpec design;
  std::optional<Measurement> protocol;
};
DesignFile load_design_file(const std::filesystem::path& path);

/// Joins shard files into exactly the unsharded output. InputError when a shard is missing,
/// repeated, from another sweep, or malformed.
std::string merge_sweep_files(const std::vector<std::filesystem::path>& files);

}  // namespace scpkit
