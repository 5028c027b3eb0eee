// scpkit map THREAD_MODEL --plies q: thread-to-thread and thread-to-SCP prediction.
#include <fmt/format.h>

#include <cmath>
#include <iostream>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "scpkit/io/atomic_file.hpp"
#include "scpkit/io/model_file.hpp"
#include "scpkit/mechanics/material.hpp"
#include "scpkit/mechanics/ply_mapping.hpp"

namespace scpkit::cli {
namespace {

constexpr const char* kUsage =
    "scpkit map THREAD_MODEL.json --plies Q [--coil-d MM --coil-D MM --coil-n N] [--data FILE] "
    "[-o OUT.csv] [--json]";
constexpr const char* kAbout =
    "Predicts the load-strain hysteresis of a Q-ply thread and of the SCP actuator made from it,\n"
    "from a model of a P-ply thread (scpkit fit on a thread test; a paired thread/SCP test also\n"
    "gives the P-ply SCP gain). Corrected physics (docs/theory.md):\n"
    "  thread:  eps_q[F] = Gamma_p[(p/q) F]                     (paper 002 Eq. 7, corrected)\n"
    "  SCP:     g_q = g_p (q/p) K_SCP,p / K_SCP,q, K = legs G d^4 / (8 n D^3), D mean diameter\n"
    "                                                             (paper 002 Eq. 8, corrected)\n"
    "with the gain's uncertainty from coil tolerances (sigma_d 0.01 mm, sigma_D 0.02 mm,\n"
    "sigma_n 5 %). The paper's equations as printed are reported alongside, labelled.\n"
    "Coils default to the material card's reference geometry for the ply count.\n"
    "With --data (a Q-ply test), predictions are compared with the measurements.";

constexpr double kGram = 9.80665e-3;

struct Prediction {
  std::string label;
  PreisachModel model;
};

}  // namespace

int run_map(const std::vector<std::string>& args) {
  po::options_description opt("options");
  opt.add_options()("help,h", "show this help")("plies,q", po::value<int>(),
                                                "target ply count Q (required)")(
      "from-plies", po::value<int>(), "ply count P of the model (default: from the model file)")(
      "coil-d", po::value<double>(), "target SCP wire diameter d, mm")(
      "coil-D", po::value<double>(), "target SCP MEAN coil diameter D, mm")(
      "coil-n", po::value<double>(), "target SCP active coils n")(
      "legs", po::value<int>()->default_value(2), "target SCP legs (1, or 2 double-backed)")(
      "material", po::value<std::string>(), "material card id (default: from the model file)")(
      "data", po::value<std::string>(), "a Q-ply test to compare with (paired, thread or SCP)")(
      "output,o", po::value<std::string>(), "CSV of the predictions")(
      "json", "print one JSON object instead of the report");
  po::variables_map vm;
  if (!parse_command_line(args, kUsage, kAbout, opt, {"MODEL"}, vm)) return kOk;
  if (!vm.count("plies")) throw UsageError("--plies Q is required");
  const ModelFile mf = load_model(vm["MODEL"].as<std::string>());
  if (mf.input != "load_N" || mf.response != "strain") {
    throw InputError(vm["MODEL"].as<std::string>(), 0, 0,
                     fmt::format("map needs a load -> strain thread model, this one is {} -> {}",
                                 mf.input, mf.response));
  }
  const int q = vm["plies"].as<int>();
  const int p = vm.count("from-plies") ? vm["from-plies"].as<int>() : mf.specimen.plies;
  if (p < 1) throw UsageError("the model file does not say its ply count: give --from-plies P");
  if (q < 1) throw UsageError("--plies must be >= 1");

  std::optional<Material> material;
  const std::string material_id =
      vm.count("material") ? vm["material"].as<std::string>() : mf.specimen.material;
  if (!material_id.empty()) material = find_material(material_id);

  // Coils: the model's own (or the card's) for p; flags (or the card's) for q.
  std::optional<CoilGeometry> coil_p = mf.specimen.coil;
  if (!coil_p && material && material->geometry_for(p)) coil_p = material->geometry_for(p)->coil;
  std::optional<CoilGeometry> coil_q;
  const int given = static_cast<int>(vm.count("coil-d") + vm.count("coil-D") + vm.count("coil-n"));
  if (given == 3) {
    CoilGeometry c;
    c.wire_d_m = vm["coil-d"].as<double>() * 1e-3;
    c.mean_D_m = vm["coil-D"].as<double>() * 1e-3;
    c.coils = vm["coil-n"].as<double>();
    c.legs = vm["legs"].as<int>();
    try {
      c.validate();
    } catch (const InvalidArgument& e) {
      throw UsageError(std::string("target coil: ") + e.what());
    }
    coil_q = c;
  } else if (given != 0) {
    throw UsageError("give all of --coil-d, --coil-D and --coil-n, or none");
  } else if (material && material->geometry_for(q)) {
    coil_q = material->geometry_for(q)->coil;
  }

  if (!mf.preisach()) {
    throw InputError(
        vm["MODEL"].as<std::string>(), 0, 0,
        fmt::format("map needs a Preisach thread model, this one is {}", mf.op.family()));
  }
  const PreisachModel& thread_p = *mf.preisach();
  std::vector<Prediction> preds;
  preds.push_back({"thread", map_thread_plies(thread_p, p, q)});
  preds.push_back({"thread_paper_eq7_as_printed", paper_eq7_as_printed(thread_p, p, q)});
  std::optional<Uncertain> gain_q;
  double gain_q_paper = 0.0;
  const CoilTolerances tol;
  const bool scp = mf.scp_gain && coil_p && coil_q;
  if (scp) {
    gain_q = predict_scp_gain(mf.scp_gain->gain, p, *coil_p, q, *coil_q, tol);
    gain_q_paper = paper_eq8_as_printed_gain(mf.scp_gain->gain, p, *coil_p, q, *coil_q);
    preds.push_back({"scp", map_thread_to_scp(thread_p, p, *mf.scp_gain, q, gain_q->value)});
    // Paper as printed: eps_SCP,q = (K_SCP,q / K_SCP,p) eps_SCP,p at equal load.
    const double ratio = spring_stiffness(1.0, *coil_q) / spring_stiffness(1.0, *coil_p);
    preds.push_back(
        {"scp_paper_eq8_as_printed",
         thread_p.with_output_affine(mf.scp_gain->gain * ratio, mf.scp_gain->offset * ratio)});
  }

  // Loads: the comparison file's, else the major loop over the scaled identified range.
  std::optional<Measurement> data;
  std::vector<double> load_N;
  if (vm.count("data")) {
    data = Measurement::read(vm["data"].as<std::string>());
    load_N = select_input(*data, "load_N").values;
  } else {
    const double lo = thread_p.grid().lo * q / p, hi = thread_p.grid().hi * q / p;
    for (int k = 0; k <= 20; ++k) load_N.push_back(lo + (hi - lo) * k / 20.0);
    for (int k = 19; k >= 0; --k) load_N.push_back(lo + (hi - lo) * k / 20.0);
  }
  std::vector<Eigen::VectorXd> out;
  for (const auto& pr : preds) {
    PreisachState s = PreisachState::negative_saturation(pr.model.grid());
    out.push_back(pr.model.simulate(s, load_N) * 100.0);  // strain-%
  }

  // Measured series for comparison.
  struct Compared {
    std::string label;
    std::size_t pred;
    ErrorMetrics err;
  };
  std::vector<Compared> compared;
  std::optional<GainFit> measured_gain;
  if (data) {
    auto series = [&](Quantity qty) -> std::optional<std::vector<double>> {
      if (const MeasurementColumn* c = data->find(qty)) return c->values;
      return std::nullopt;
    };
    std::optional<std::vector<double>> thread_meas = series(Quantity::kThreadStrain);
    std::optional<std::vector<double>> scp_meas = series(Quantity::kScpStrain);
    if (!thread_meas && !scp_meas) {
      const Signal r = select_response(*data, "");
      if (r.name != "strain")
        throw InputError(data->source(), data->header_line(), 0,
                         "the comparison data need strain (or disp_mm with length_mm)");
      const std::string specimen = data->meta("specimen").value_or("thread");
      (specimen == "scp" ? scp_meas : thread_meas) = r.values;
    }
    if (thread_meas && scp_meas) measured_gain = fit_scp_gain(*thread_meas, *scp_meas);
    for (std::size_t k = 0; k < preds.size(); ++k) {
      const bool is_scp = preds[k].label.rfind("scp", 0) == 0;
      const auto& meas = is_scp ? scp_meas : thread_meas;
      if (!meas) continue;
      std::vector<double> pct(meas->size());
      for (std::size_t i = 0; i < pct.size(); ++i) pct[i] = 100.0 * (*meas)[i];
      compared.push_back({preds[k].label, k,
                          error_metrics(pct, std::span<const double>(out[k].data(), pct.size()))});
    }
  }

  if (vm.count("output")) {
    std::ostringstream csv;
    csv << "# scpkit map: " << p << "-ply model -> " << q << " plies; strains in %\n";
    csv << "load_g";
    for (const auto& pr : preds) csv << ",predicted_" << pr.label << "_strain_pct";
    if (gain_q) csv << ",scp_band_lo_strain_pct,scp_band_hi_strain_pct";
    csv << "\n";
    for (std::size_t i = 0; i < load_N.size(); ++i) {
      csv << csv_number(load_N[i] / kGram);
      for (const auto& o : out) csv << "," << csv_number(o[static_cast<Eigen::Index>(i)]);
      if (gain_q) {
        const double v = out[2][static_cast<Eigen::Index>(i)];
        const double band = std::abs(v) * gain_q->relative();
        csv << "," << csv_number(v - band) << "," << csv_number(v + band);
      }
      csv << "\n";
    }
    write_file_atomically(vm["output"].as<std::string>(), csv.str());
  }

  if (vm.count("json")) {
    nlohmann::json j;
    j["from_plies"] = p;
    j["to_plies"] = q;
    j["input_scale"] = static_cast<double>(p) / q;
    if (scp) {
      j["stiffness_ratio_p_over_q"] =
          spring_stiffness(1.0, *coil_p) / spring_stiffness(1.0, *coil_q);
      j["gain_p"] = mf.scp_gain->gain;
      j["gain_q"] = {{"value", gain_q->value}, {"sigma", gain_q->sigma}};
      j["gain_q_paper_eq8_as_printed"] = gain_q_paper;
      if (!coil_q->caution().empty()) j["caution"] = coil_q->caution();
    }
    if (measured_gain)
      j["gain_q_measured"] = {{"value", measured_gain->gain}, {"r2", measured_gain->r2}};
    nlohmann::json cmp = nlohmann::json::object();
    for (const auto& c : compared) cmp[c.label] = metrics_json(c.err);
    j["errors"] = cmp;
    if (vm.count("output")) j["output_file"] = vm["output"].as<std::string>();
    print_json(j);
    return kOk;
  }

  std::cout << fmt::format("map: {}-ply thread model -> {} plies (per-ply load scaling {:.4g})\n",
                           p, q, static_cast<double>(p) / q);
  if (scp) {
    const Uncertain ratio = stiffness_ratio(*coil_p, *coil_q, tol);
    std::cout << fmt::format(
        "  coil {}-ply: d {:.3g} mm, D {:.3g} mm (mean), n {:g}, {} legs;  coil {}-ply: d {:.3g} "
        "mm, D {:.3g} mm, n {:g}, {} legs\n",
        p, coil_p->wire_d_m * 1e3, coil_p->mean_D_m * 1e3, coil_p->coils, coil_p->legs, q,
        coil_q->wire_d_m * 1e3, coil_q->mean_D_m * 1e3, coil_q->coils, coil_q->legs);
    std::cout << fmt::format("  K_SCP,{} / K_SCP,{} = {:.4f} +- {:.4f}\n", p, q, ratio.value,
                             ratio.sigma);
    std::cout << fmt::format(
        "  SCP gain: g_{} = {:.4f} (fitted)  ->  g_{} = {:.4f} +- {:.4f} (corrected Eq. 8)", p,
        mf.scp_gain->gain, q, gain_q->value, gain_q->sigma);
    std::cout << fmt::format("   [paper Eq. 8 as printed: {:.4f}]\n", gain_q_paper);
    if (measured_gain) {
      std::cout << fmt::format(
          "  measured g_{} = {:.4f} (R^2 {:.5f}): corrected {:+.1f} %, as printed {:+.1f} %\n", q,
          measured_gain->gain, measured_gain->r2,
          100.0 * (gain_q->value / measured_gain->gain - 1.0),
          100.0 * (gain_q_paper / measured_gain->gain - 1.0));
    }
    if (!coil_q->caution().empty()) std::cout << "  caution: " << coil_q->caution() << "\n";
  } else {
    std::cout
        << "  (no SCP prediction: needs a paired thread/SCP model and both coil geometries)\n";
  }
  if (compared.empty()) {
    const auto& t = out[0];
    std::cout << fmt::format(
        "  predicted {}-ply thread major loop: strain {:.3f} .. {:.3f} % over {:.4g} .. {:.4g} g\n",
        q, t.minCoeff(), t.maxCoeff(), load_N.front() / kGram, load_N[20] / kGram);
    if (scp) {
      std::cout << fmt::format(
          "  predicted {}-ply SCP major loop: strain {:.2f} .. {:.2f} % (+- {:.0f} % from coil "
          "tolerances)\n",
          q, out[2].minCoeff(), out[2].maxCoeff(), 100.0 * gain_q->relative());
    }
  } else {
    std::cout << fmt::format("  against {} ({} readings):\n", data->source(), load_N.size());
    for (const auto& c : compared) {
      std::cout << fmt::format("    {:<28} {}\n", c.label, c.err.brief("strain-%"));
    }
  }
  if (vm.count("output"))
    std::cout << "  predictions written to " << vm["output"].as<std::string>() << "\n";
  return kOk;
}

}  // namespace scpkit::cli
