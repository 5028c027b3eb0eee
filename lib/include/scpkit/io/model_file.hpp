#pragma once
// Model files (JSON, format "scpkit-model" version 1): an identified operator with the units
// of its input and response, what specimen it describes, and how well it fitted. Canonical
// units inside: input in N, V, W or C; response as strain (fraction) or mm. docs/data-format.md.
#include <filesystem>
#include <optional>
#include <string>

#include "scpkit/hysteresis/augmented.hpp"
#include "scpkit/hysteresis/operator.hpp"
#include "scpkit/hysteresis/preisach.hpp"
#include "scpkit/identification/preisach_fit.hpp"
#include "scpkit/mechanics/coil.hpp"
#include "scpkit/mechanics/ply_mapping.hpp"
#include "scpkit/metrics.hpp"

namespace scpkit {

struct SpecimenInfo {
  std::string specimen;  ///< "thread", "scp", or another word; "" when unknown
  std::string material;  ///< material card id, "" when unknown
  int plies = 0;         ///< 0 when unknown
  double length_mm = 0.0;
  std::optional<CoilGeometry> coil;  ///< the SCP made from this thread, when known
};

struct ModelFile {
  std::string input;            ///< canonical input name (load_N, voltage_V, power_W, temp_C)
  std::string response;         ///< canonical response (strain or disp_mm)
  std::string response_column;  ///< the data column it was fitted to, e.g. thread_strain_pct
  HysteresisOperator op{
      PreisachModel{PreisachGrid{}, Eigen::VectorXd::Zero(PreisachGrid{}.cells()), 0.0}};
  /// The Preisach model, or nullptr for another family.
  const PreisachModel* preisach() const { return std::get_if<PreisachModel>(&op.model()); }
  /// Voltage tests under several loads: y = f2(F) op[v] + f1(F) (its h is op).
  std::optional<AugmentedModel> augmented;
  SpecimenInfo specimen;
  std::optional<GainFit> scp_gain;  ///< SCP strain vs thread strain, from paired data
  ErrorMetrics fit_metrics;
  double cv_rms_pct_range = -1.0;
  std::string data_file;  ///< the identification data, for the record
};

/// Writes atomically. InputError when the file cannot be written.
void save_model(const std::filesystem::path& path, const ModelFile& m);
/// Reads and validates. InputError naming the file (and the JSON position when it is not JSON).
ModelFile load_model(const std::filesystem::path& path);

}  // namespace scpkit
