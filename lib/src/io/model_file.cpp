#include "scpkit/io/model_file.hpp"

#include <nlohmann/json.hpp>

#include "scpkit/error.hpp"
#include "scpkit/io/atomic_file.hpp"
#include "scpkit/version.hpp"

namespace scpkit {

using nlohmann::json;

namespace {

json operator_json(const HysteresisOperator& op) {
  json j;
  j["family"] = op.family();
  j["input_range"] = {op.input_min(), op.input_max()};
  if (const auto* p = std::get_if<PreisachModel>(&op.model())) {
    const PreisachGrid& g = p->grid();
    j["preisach"] = {
        {"lo", g.lo},
        {"hi", g.hi},
        {"levels", g.levels},
        {"bias", p->bias()},
        {"weights", std::vector<double>(p->weights().begin(), p->weights().end())},
        {"weights_are", "cell masses, row-major over beta level i then alpha level j >= i"}};
  } else if (const auto* l = std::get_if<LonelyModel>(&op.model())) {
    const PreisachGrid& g = l->preisach.grid();
    j["preisach"] = {{"lo", g.lo},
                     {"hi", g.hi},
                     {"levels", g.levels},
                     {"bias", l->preisach.bias()},
                     {"weights", std::vector<double>(l->preisach.weights().begin(),
                                                     l->preisach.weights().end())}};
    j["running_max_weights"] = l->column_weights;
  } else if (const auto* m = std::get_if<GpiModel>(&op.model())) {
    j["gpi"] = {{"right", {{"a", m->right.a}, {"b", m->right.b}}},
                {"left", {{"a", m->left.a}, {"b", m->left.b}}},
                {"radii", m->radii},
                {"weights", m->weights},
                {"bias", m->bias},
                {"v_min", m->v_min},
                {"v_max", m->v_max}};
  } else {
    const auto& poly = std::get<PolynomialModel>(op.model());
    j["polynomial"] = {
        {"coefficients", poly.coefficients}, {"v_min", poly.v_min}, {"v_max", poly.v_max}};
  }
  return j;
}

HysteresisOperator operator_from_json(const json& j) {
  const std::string family = j.at("family").get<std::string>();
  if (family == "preisach" || family == "lonely") {
    const json& p = j.at("preisach");
    PreisachGrid g{p.at("lo").get<double>(), p.at("hi").get<double>(), p.at("levels").get<int>()};
    const auto w = p.at("weights").get<std::vector<double>>();
    PreisachModel model(
        g, Eigen::Map<const Eigen::VectorXd>(w.data(), static_cast<Eigen::Index>(w.size())),
        p.at("bias").get<double>());
    if (family == "lonely") {
      LonelyModel l{std::move(model), j.at("running_max_weights").get<std::vector<double>>()};
      l.validate();
      const auto r = j.at("input_range").get<std::vector<double>>();
      if (r.size() != 2) throw InvalidArgument("input_range must be [min, max]");
      return HysteresisOperator(std::move(l), r[0], r[1]);
    }
    if (j.contains("input_range")) {
      const auto r = j.at("input_range").get<std::vector<double>>();
      if (r.size() != 2) throw InvalidArgument("input_range must be [min, max]");
      return HysteresisOperator(std::move(model), r[0], r[1]);
    }
    return HysteresisOperator(std::move(model));
  }
  if (family == "gpi") {
    const json& p = j.at("gpi");
    GpiModel m;
    m.right = {p.at("right").at("a").get<double>(), p.at("right").at("b").get<double>()};
    m.left = {p.at("left").at("a").get<double>(), p.at("left").at("b").get<double>()};
    m.radii = p.at("radii").get<std::vector<double>>();
    m.weights = p.at("weights").get<std::vector<double>>();
    m.bias = p.at("bias").get<double>();
    m.v_min = p.at("v_min").get<double>();
    m.v_max = p.at("v_max").get<double>();
    m.validate();
    return HysteresisOperator(m);
  }
  if (family == "linear" || family == "poly2") {
    const json& p = j.at("polynomial");
    PolynomialModel poly;
    poly.coefficients = p.at("coefficients").get<std::vector<double>>();
    poly.v_min = p.at("v_min").get<double>();
    poly.v_max = p.at("v_max").get<double>();
    if (poly.coefficients.size() != (family == "linear" ? 2u : 3u) || !(poly.v_min < poly.v_max)) {
      throw InvalidArgument("polynomial model: wrong number of coefficients or empty range");
    }
    return HysteresisOperator(poly);
  }
  throw InvalidArgument("unknown operator family '" + family + "'");
}

}  // namespace

void save_model(const std::filesystem::path& path, const ModelFile& m) {
  json j;
  j["format"] = "scpkit-model";
  j["version"] = 1;
  j["scpkit"] = kVersion;
  j["model"] = m.op.family();  // "augmented" below when load maps are present
  j["input"] = m.input;
  j["response"] = m.response;
  j["response_column"] = m.response_column;
  j["operator"] = operator_json(m.op);
  if (m.augmented) {
    const AugmentedModel& a = *m.augmented;
    j["model"] = "augmented";
    j["augmented"] = {
        {"f1", {a.f1.c0, a.f1.c1, a.f1.c2}},
        {"f2", {a.f2.c0, a.f2.c1, a.f2.c2}},
        {"load_range_N", {a.load_min, a.load_max}},
        {"form", "y = f2(F) * H[input] + f1(F), f = c0 + c1 F + c2 F^2, F in N, H = operator"}};
  }
  json s;
  s["specimen"] = m.specimen.specimen;
  s["material"] = m.specimen.material;
  s["plies"] = m.specimen.plies;
  s["length_mm"] = m.specimen.length_mm;
  if (m.specimen.coil) {
    const CoilGeometry& c = *m.specimen.coil;
    s["coil"] = {
        {"d_mm", c.wire_d_m * 1e3}, {"D_mm", c.mean_D_m * 1e3}, {"n", c.coils}, {"legs", c.legs}};
  }
  j["specimen"] = s;
  if (m.scp_gain) {
    j["scp_gain"] = {{"gain", m.scp_gain->gain},
                     {"offset", m.scp_gain->offset},
                     {"r2", m.scp_gain->r2},
                     {"samples", m.scp_gain->samples}};
  }
  j["fit"] = {{"rms_pct_range", m.fit_metrics.rms_pct_range},
              {"max_pct_range", m.fit_metrics.max_pct_range},
              {"mean_abs", m.fit_metrics.mean_abs},
              {"sd_abs", m.fit_metrics.sd_abs},
              {"cv_rms_pct_range", m.cv_rms_pct_range},
              {"data_file", m.data_file}};
  write_file_atomically(path, j.dump(2) + "\n");
}

ModelFile load_model(const std::filesystem::path& path) {
  const std::string name = path.string();
  const std::string text = read_text_file(path);
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    // Byte offset -> line and column.
    int line = 1, col = 1;
    for (std::size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
      if (text[i] == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
    throw InputError(name, line, col, "not a JSON model file");
  }
  try {
    if (j.value("format", "") != "scpkit-model")
      throw InputError(name, 0, 0, "not an scpkit model file (format is not 'scpkit-model')");
    if (j.value("version", 0) != 1) throw InputError(name, 0, 0, "unsupported model file version");
    ModelFile m;
    m.input = j.at("input").get<std::string>();
    m.response = j.at("response").get<std::string>();
    m.response_column = j.value("response_column", "");
    if (m.response != "strain" && m.response != "disp_mm")
      throw InputError(name, 0, 0, "unknown response '" + m.response + "'");
    m.op = operator_from_json(j.at("operator"));
    if (j.contains("augmented")) {
      const json& a = j.at("augmented");
      const auto f1 = a.at("f1").get<std::vector<double>>(),
                 f2 = a.at("f2").get<std::vector<double>>();
      const auto range = a.at("load_range_N").get<std::vector<double>>();
      if (f1.size() != 3 || f2.size() != 3 || range.size() != 2)
        throw InvalidArgument("augmented maps need 3 coefficients and a [min, max] load range");
      AugmentedModel am;
      am.f1 = {f1[0], f1[1], f1[2]};
      am.f2 = {f2[0], f2[1], f2[2]};
      am.load_min = range[0];
      am.load_max = range[1];
      am.h = m.op;
      am.validate();
      m.augmented = am;
    }
    const json& s = j.at("specimen");
    m.specimen.specimen = s.value("specimen", "");
    m.specimen.material = s.value("material", "");
    m.specimen.plies = s.value("plies", 0);
    m.specimen.length_mm = s.value("length_mm", 0.0);
    if (s.contains("coil")) {
      const json& c = s.at("coil");
      CoilGeometry coil;
      coil.wire_d_m = c.at("d_mm").get<double>() * 1e-3;
      coil.mean_D_m = c.at("D_mm").get<double>() * 1e-3;
      coil.coils = c.at("n").get<double>();
      coil.legs = c.value("legs", 1);
      coil.validate();
      m.specimen.coil = coil;
    }
    if (j.contains("scp_gain")) {
      const json& gj = j.at("scp_gain");
      m.scp_gain = GainFit{gj.at("gain").get<double>(), gj.at("offset").get<double>(),
                           gj.at("r2").get<double>(), gj.at("samples").get<int>()};
    }
    const json& f = j.at("fit");
    m.fit_metrics.rms_pct_range = f.value("rms_pct_range", 0.0);
    m.fit_metrics.max_pct_range = f.value("max_pct_range", 0.0);
    m.fit_metrics.mean_abs = f.value("mean_abs", 0.0);
    m.fit_metrics.sd_abs = f.value("sd_abs", 0.0);
    m.cv_rms_pct_range = f.value("cv_rms_pct_range", -1.0);
    m.data_file = f.value("data_file", "");
    return m;
  } catch (const json::exception& e) {
    throw InputError(name, 0, 0, std::string("malformed model file: ") + e.what());
  } catch (const InvalidArgument& e) {
    throw InputError(name, 0, 0, std::string("invalid model: ") + e.what());
  }
}

}  // namespace scpkit
