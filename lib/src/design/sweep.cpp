#include "scpkit/design/sweep.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "../io/toml_reader.hpp"
#include "scpkit/error.hpp"
#include "scpkit/io/atomic_file.hpp"
#include "scpkit/io/model_file.hpp"

namespace scpkit {
namespace {

constexpr double kGram = 9.80665e-3;

// splitmix64: a counter-based generator, so sample i never depends on the others.
std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

struct Uniform {
  std::uint64_t state;
  double operator()() {
    state = splitmix(state);
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  }
};

// A row's numbers, written as fmt's "{:.6g}" (printf's %.6g) writes them: std::to_chars in the
// general format at precision 6 gives the same characters (checked on 2 million values of every
// magnitude, zeros, infinities and NaN) in about half the time, and the rows' formatting was
// most of a design's cost in the sweep.
void put_g6(std::string& out, double v) {
  char buf[32];
  const auto end = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 6).ptr;
  out.append(buf, end);
}

template <class Integer>
void put_integer(std::string& out, Integer v) {
  char buf[24];
  out.append(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

const std::vector<std::string>& columns() {
  static const std::vector<std::string> c = {"index",
                                             "plies",
                                             "d_mm",
                                             "D_mm",
                                             "n",
                                             "legs",
                                             "length_mm",
                                             "spring_index",
                                             "pitch_mm",
                                             "stiffness_N_per_m",
                                             "stiffness_sigma_N_per_m",
                                             "gain",
                                             "gain_sigma",
                                             "stroke_mm",
                                             "stroke_sigma_mm",
                                             "stroke_pct",
                                             "hysteresis_pct",
                                             "thermal_stroke_mm",
                                             "voltage_for_target_V",
                                             "voltage_extrapolated",
                                             "feasible",
                                             "reason"};
  return c;
}

int column_index(const std::string& name) {
  const auto& c = columns();
  const auto it = std::find(c.begin(), c.end(), name);
  return it == c.end() ? -1 : static_cast<int>(it - c.begin());
}

std::string field(const std::string& row, int index) {
  std::size_t start = 0;
  for (int i = 0; i < index; ++i) start = row.find(',', start) + 1;
  const std::size_t end = row.find(',', start);
  return row.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

double number(const std::string& s) {
  double v = 0.0;
  std::from_chars(s.data(), s.data() + s.size(), v);
  return v;
}

SweepAxis axis(const detail::TomlReader& r, const toml::table& t, const char* key,
               SweepAxis fallback, double min) {
  const toml::node* n = t.get(key);
  if (!n) return fallback;
  SweepAxis a;
  if (const toml::array* arr = n->as_array()) {
    for (const toml::node& x : *arr) {
      const auto v = x.value<double>();
      if (!v || !(*v >= min))
        r.fail(&x, fmt::format("'{}' values must be numbers >= {}", key, min));
      a.values.push_back(*v);
    }
  } else if (const toml::table* g = n->as_table()) {
    r.only_keys(*g, {"from", "to", "steps"});
    const double from = r.number(*g, "from", 0.0, min, true),
                 to = r.number(*g, "to", 0.0, min, true);
    const int steps = static_cast<int>(r.integer(*g, "steps", 2, 1, 100000));
    for (int k = 0; k < steps; ++k)
      a.values.push_back(steps == 1 ? from : from + (to - from) * k / (steps - 1));
  } else if (const auto v = n->value<double>()) {
    if (!(*v >= min)) r.fail(n, fmt::format("'{}' must be >= {}", key, min));
    a.values.push_back(*v);
  } else {
    r.fail(n, fmt::format("'{}' must be a number, a list, or {{from, to, steps}}", key));
  }
  if (a.values.empty()) r.fail(n, fmt::format("'{}' is empty", key));
  return a;
}

std::vector<int> int_list(const detail::TomlReader& r, const toml::table& t, const char* key,
                          std::vector<int> fallback, int min, int max) {
  const toml::node* n = t.get(key);
  if (!n) return fallback;
  std::vector<int> out;
  auto take = [&](const toml::node& x) {
    const auto v = x.value<long long>();
    if (!x.is_integer() || !v || *v < min || *v > max)
      r.fail(&x, fmt::format("'{}' must hold integers {}..{}", key, min, max));
    out.push_back(static_cast<int>(*v));
  };
  if (const toml::array* arr = n->as_array()) {
    for (const toml::node& x : *arr) take(x);
  } else {
    take(*n);
  }
  if (out.empty()) r.fail(n, fmt::format("'{}' is empty", key));
  return out;
}

}  // namespace

double SweepAxis::min() const { return *std::min_element(values.begin(), values.end()); }
double SweepAxis::max() const { return *std::max_element(values.begin(), values.end()); }

std::size_t SweepSpec::grid_count() const {
  if (!grid) return 0;
  return plies.size() * (wire_d_mm ? wire_d_mm->values.size() : 1) * spring_index.values.size() *
         coils.values.size() * legs.size() * length_mm.values.size();
}

std::size_t SweepSpec::candidate_count() const {
  return grid_count() + static_cast<std::size_t>(random_samples);
}

SweepSpec load_sweep_spec(const std::filesystem::path& path) {
  using detail::TomlReader;
  const toml::table root = TomlReader::parse(path);
  const TomlReader r(path.string());
  r.only_keys(root, {"thread_model", "voltage_model", "material", "seed", "random_samples", "grid",
                     "space", "loads", "constraints", "objective", "tolerances"});
  SweepSpec s;
  const std::filesystem::path dir = path.parent_path();
  s.thread_model = dir / r.text(root, "thread_model", "", true);
  if (root.get("voltage_model")) s.voltage_model = dir / r.text(root, "voltage_model", "");
  s.material = r.text(root, "material", "");
  s.seed = static_cast<std::uint64_t>(r.integer(root, "seed", 1, 0, 1LL << 62));
  s.random_samples = r.integer(root, "random_samples", 0, 0, 100000000);
  s.grid = r.boolean(root, "grid", true);
  if (const toml::table* t = r.table(root, "space")) {
    r.only_keys(*t, {"plies", "d_mm", "spring_index", "n", "legs", "length_mm"});
    s.plies = int_list(r, *t, "plies", s.plies, 1, 100);
    if (t->get("d_mm")) s.wire_d_mm = axis(r, *t, "d_mm", {}, 1e-6);
    s.spring_index = axis(r, *t, "spring_index", s.spring_index, 0.0);
    s.coils = axis(r, *t, "n", s.coils, 1e-6);
    s.legs = int_list(r, *t, "legs", s.legs, 1, 2);
    s.length_mm = axis(r, *t, "length_mm", s.length_mm, 1e-6);
  }
  if (const toml::table* t = r.table(root, "loads")) {
    r.only_keys(*t, {"min_g", "max_g", "protocol_steps", "working_g", "target_stroke_mm"});
    s.load_min_g = r.number(*t, "min_g", s.load_min_g, 0.0);
    s.load_max_g = r.positive(*t, "max_g", s.load_max_g, false);
    s.protocol_steps =
        static_cast<int>(r.integer(*t, "protocol_steps", s.protocol_steps, 2, 100000));
    s.working_load_g = r.number(*t, "working_g", 0.0, 0.0);
    s.target_stroke_mm = r.number(*t, "target_stroke_mm", 0.0, 0.0);
    if (!(s.load_max_g > s.load_min_g)) r.fail(t, "max_g must exceed min_g");
  }
  if (const toml::table* t = r.table(root, "constraints")) {
    r.only_keys(*t, {"min_stroke_mm", "max_hysteresis_pct", "max_stiffness_N_per_m",
                     "min_thermal_stroke_mm", "max_voltage_V", "max_strain_pct"});
    s.max_strain_pct = r.positive(*t, "max_strain_pct", s.max_strain_pct, false);
    s.min_stroke_mm = r.number(*t, "min_stroke_mm", 0.0, 0.0);
    s.max_hysteresis_pct = r.number(*t, "max_hysteresis_pct", 0.0, 0.0);
    s.max_stiffness_N_per_m = r.number(*t, "max_stiffness_N_per_m", 0.0, 0.0);
    s.min_thermal_stroke_mm = r.number(*t, "min_thermal_stroke_mm", 0.0, 0.0);
    s.max_voltage_V = r.number(*t, "max_voltage_V", 0.0, 0.0);
  }
  if (const toml::table* t = r.table(root, "objective")) {
    r.only_keys(*t, {"maximize", "minimize"});
    if (t->get("maximize") && t->get("minimize")) r.fail(t, "give maximize or minimize, not both");
    s.maximize = t->get("maximize") != nullptr;
    s.objective = r.text(*t, s.maximize ? "maximize" : "minimize", s.objective, true);
    const int c = column_index(s.objective);
    if (c < 0 || s.objective == "reason" || s.objective == "index") {
      r.fail(t->get(s.maximize ? "maximize" : "minimize"),
             fmt::format("'{}' is not a numeric output column", s.objective));
    }
  }
  if (const toml::table* t = r.table(root, "tolerances")) {
    r.only_keys(*t, {"d_mm", "D_mm", "n_rel"});
    s.tolerances.wire_d_m = r.number(*t, "d_mm", 0.01, 0.0) * 1e-3;
    s.tolerances.mean_D_m = r.number(*t, "D_mm", 0.02, 0.0) * 1e-3;
    s.tolerances.coils_rel = r.number(*t, "n_rel", 0.05, 0.0);
  }
  if (s.candidate_count() == 0)
    r.fail(nullptr, "the sweep has no candidates (grid = false and random_samples = 0)");
  return s;
}

SweepContext prepare_sweep(const SweepSpec& spec) {
  SweepContext ctx{spec, {}, {}};
  const ModelFile mf = load_model(spec.thread_model);
  const std::string name = spec.thread_model.string();
  if (!mf.preisach() || mf.input != "load_N" || mf.response != "strain") {
    throw InputError(
        name, 0, 0,
        "the thread model must be a load -> strain Preisach model (scpkit fit on a thread test)");
  }
  if (!mf.scp_gain)
    throw InputError(name, 0, 0,
                     "the thread model has no SCP gain: fit it on a paired thread/SCP test");
  if (mf.specimen.plies < 1)
    throw InputError(name, 0, 0, "the thread model does not say its ply count (plies metadata)");
  ThreadCharacterisation& ch = ctx.characterisation;
  ch.thread = *mf.preisach();
  ch.plies = mf.specimen.plies;
  ch.scp_gain = *mf.scp_gain;
  ch.load_min_N = mf.op.input_min();
  ch.load_max_N = mf.op.input_max();
  ctx.material = find_material(spec.material.empty() ? mf.specimen.material : spec.material);
  if (mf.specimen.coil) {
    ch.coil = *mf.specimen.coil;
  } else if (const ReferenceGeometry* g = ctx.material.geometry_for(ch.plies)) {
    ch.coil = g->coil;
  } else {
    throw InputError(
        name, 0, 0, "the characterised SCP's coil is unknown (coil metadata or the material card)");
  }
  ch.coil.length_m = mf.specimen.length_mm > 0.0 ? mf.specimen.length_mm * 1e-3 : ch.coil.length_m;
  if (!spec.voltage_model.empty()) {
    const ModelFile vm = load_model(spec.voltage_model);
    if (!vm.augmented || vm.response != "strain") {
      throw InputError(spec.voltage_model.string(), 0, 0,
                       "the voltage model must be an augmented model with a strain response");
    }
    ch.voltage = vm.augmented;
    ch.voltage_length_mm = vm.specimen.length_mm;
    ch.voltage_plies = vm.specimen.plies > 0 ? vm.specimen.plies : ch.plies;
    if (!(ch.voltage_length_mm > 0.0))
      throw InputError(spec.voltage_model.string(), 0, 0, "the voltage model needs length_mm");
  }
  return ctx;
}

DesignFile load_design_file(const std::filesystem::path& path) {
  using detail::TomlReader;
  const toml::table root = TomlReader::parse(path);
  const TomlReader r(path.string());
  r.only_keys(root, {"thread_model", "voltage_model", "material", "plies", "coil", "loads",
                     "protocol_file"});
  const std::filesystem::path dir = path.parent_path();
  SweepSpec spec;
  spec.thread_model = dir / r.text(root, "thread_model", "", true);
  if (root.get("voltage_model")) spec.voltage_model = dir / r.text(root, "voltage_model", "");
  spec.material = r.text(root, "material", "");
  DesignFile f{prepare_sweep(spec), {}, std::nullopt};
  DesignSpec& d = f.design;
  d.plies = static_cast<int>(r.integer(root, "plies", 0, 1, 100));
  if (d.plies == 0) r.fail(&root, "missing key 'plies'");
  const toml::table& coil = *r.table(root, "coil", true);
  r.only_keys(coil, {"d_mm", "D_mm", "spring_index", "n", "legs", "length_mm"});
  const double dmm = r.number(coil, "d_mm", 0.0, 0.0);
  d.coil.wire_d_m =
      dmm > 0.0 ? dmm * 1e-3
                : wire_diameter_for(f.context.material, f.context.characterisation, d.plies);
  d.coil.mean_D_m = coil.get("D_mm") ? r.positive(coil, "D_mm") * 1e-3
                                     : r.positive(coil, "spring_index") * d.coil.wire_d_m;
  d.coil.coils = r.positive(coil, "n");
  d.coil.legs = static_cast<int>(r.integer(coil, "legs", 2, 1, 2));
  d.coil.length_m = r.positive(coil, "length_mm") * 1e-3;
  if (const toml::table* loads = r.table(root, "loads")) {
    r.only_keys(*loads, {"min_g", "max_g", "protocol_steps", "working_g", "target_stroke_mm"});
    d.load_min_N = r.number(*loads, "min_g", 0.0, 0.0, true) * kGram;
    d.load_max_N = r.number(*loads, "max_g", 0.0, 0.0, true) * kGram;
    d.protocol_steps = static_cast<int>(r.integer(*loads, "protocol_steps", 100, 2, 100000));
    d.working_load_N = r.number(*loads, "working_g", 0.0, 0.0) * kGram;
    d.target_stroke_mm = r.number(*loads, "target_stroke_mm", 0.0, 0.0);
  }
  if (root.get("protocol_file")) {
    f.protocol = Measurement::read(dir / r.text(root, "protocol_file", ""));
    d.protocol_N = select_input(*f.protocol, "load").values;
  } else if (!(d.load_max_N > 0.0)) {
    r.fail(&root, "give [loads] min_g and max_g, or a protocol_file");
  }
  return f;
}

DesignSpec sweep_candidate(const SweepContext& ctx, std::size_t index) {
  const SweepSpec& s = ctx.spec;
  DesignSpec d;
  double C, n, length, dmm = 0.0;
  int legs;
  if (index < s.grid_count()) {
    std::size_t i = index;
    auto pick = [&i](std::size_t count) {
      const std::size_t k = i % count;
      i /= count;
      return k;
    };
    d.plies = s.plies[pick(s.plies.size())];
    if (s.wire_d_mm) dmm = s.wire_d_mm->values[pick(s.wire_d_mm->values.size())];
    C = s.spring_index.values[pick(s.spring_index.values.size())];
    n = s.coils.values[pick(s.coils.values.size())];
    legs = s.legs[pick(s.legs.size())];
    length = s.length_mm.values[pick(s.length_mm.values.size())];
  } else {
    Uniform u{splitmix(s.seed) ^ (index - s.grid_count()) * 0xd1b54a32d192ed03ULL};
    auto span = [&u](const SweepAxis& a) { return a.min() + (a.max() - a.min()) * u(); };
    d.plies = s.plies[static_cast<std::size_t>(u() * static_cast<double>(s.plies.size())) %
                      s.plies.size()];
    if (s.wire_d_mm) dmm = span(*s.wire_d_mm);
    C = span(s.spring_index);
    n = std::round(span(s.coils));
    legs =
        s.legs[static_cast<std::size_t>(u() * static_cast<double>(s.legs.size())) % s.legs.size()];
    length = span(s.length_mm);
  }
  d.coil.wire_d_m =
      dmm > 0.0 ? dmm * 1e-3 : wire_diameter_for(ctx.material, ctx.characterisation, d.plies);
  d.coil.mean_D_m = C * d.coil.wire_d_m;
  d.coil.coils = n;
  d.coil.legs = legs;
  d.coil.length_m = length * 1e-3;
  // Working loads are given for two plies, like the paper's protocol, and scale with plies.
  d.load_min_N = s.load_min_g * kGram * d.plies / 2.0;
  d.load_max_N = s.load_max_g * kGram * d.plies / 2.0;
  d.protocol_steps = s.protocol_steps;
  d.working_load_N = s.working_load_g * kGram;
  d.target_stroke_mm = s.target_stroke_mm;
  d.tolerances = s.tolerances;
  d.max_strain_pct = s.max_strain_pct;
  return d;
}

std::string sweep_header() {
  std::string h;
  for (const auto& c : columns()) h += (h.empty() ? "" : ",") + c;
  return h;
}

std::string sweep_row(const SweepContext& ctx, std::size_t index, const DesignSpec& d,
                      const DesignResult& r) {
  const SweepSpec& s = ctx.spec;
  std::string reason = r.reason;
  bool ok = r.feasible;
  auto fail = [&](std::string why) {
    if (ok) {
      ok = false;
      reason = std::move(why);
    }
  };
  if (s.min_stroke_mm > 0 && std::abs(r.stroke_mm) < s.min_stroke_mm)
    fail(fmt::format("stroke {:.3g} mm < {:g} mm", std::abs(r.stroke_mm), s.min_stroke_mm));
  if (s.max_hysteresis_pct > 0 && r.hysteresis_pct > s.max_hysteresis_pct)
    fail(fmt::format("hysteresis {:.3g} % > {:g} %", r.hysteresis_pct, s.max_hysteresis_pct));
  if (s.max_stiffness_N_per_m > 0 && r.stiffness_N_per_m.value > s.max_stiffness_N_per_m)
    fail(fmt::format("stiffness {:.3g} N/m > {:g} N/m", r.stiffness_N_per_m.value,
                     s.max_stiffness_N_per_m));
  if (s.min_thermal_stroke_mm > 0 && r.thermal_stroke_mm < s.min_thermal_stroke_mm)
    fail(fmt::format("thermal stroke {:.3g} mm < {:g} mm", r.thermal_stroke_mm,
                     s.min_thermal_stroke_mm));
  if (s.max_voltage_V > 0 && s.target_stroke_mm > 0 &&
      (r.voltage_for_target_V < 0 || r.voltage_for_target_V > s.max_voltage_V)) {
    fail(r.voltage_for_target_V < 0
             ? std::string("target stroke unreachable")
             : fmt::format("voltage {:.3g} V > {:g} V", r.voltage_for_target_V, s.max_voltage_V));
  }
  std::replace(reason.begin(), reason.end(), ',', ';');
  std::string row;
  row.reserve(224 + reason.size());
  put_integer(row, index);
  row += ',';
  put_integer(row, d.plies);
  for (const double v : {d.coil.wire_d_m * 1e3, d.coil.mean_D_m * 1e3, d.coil.coils}) {
    row += ',';
    put_g6(row, v);
  }
  row += ',';
  put_integer(row, d.coil.legs);
  for (const double v :
       {d.coil.length_m * 1e3, r.spring_index, r.pitch_mm, r.stiffness_N_per_m.value,
        r.stiffness_N_per_m.sigma, r.gain.value, r.gain.sigma, r.stroke_mm, r.stroke_sigma_mm,
        r.stroke_pct, r.hysteresis_pct, r.thermal_stroke_mm, r.voltage_for_target_V}) {
    row += ',';
    put_g6(row, v);
  }
  row += r.voltage_extrapolated ? ",1" : ",0";
  row += ok ? ",1," : ",0,";
  row += reason;
  return row;
}

std::vector<std::string> run_sweep(const SweepContext& ctx, int shard, int shards, int threads,
                                   const std::function<void(std::size_t, std::size_t)>& progress) {
  if (shards < 1 || shard < 0 || shard >= shards)
    throw_invalid("shard {}/{} does not exist", shard, shards);
  const std::size_t total = ctx.spec.candidate_count();
  std::vector<std::size_t> mine;
  for (std::size_t i = static_cast<std::size_t>(shard); i < total;
       i += static_cast<std::size_t>(shards))
    mine.push_back(i);
  std::vector<std::string> rows(mine.size());
  std::atomic<std::size_t> next{0}, done{0};
  const std::size_t chunk = 256;
  auto worker = [&] {
    DesignWorkspace ws;
    for (;;) {
      const std::size_t begin = next.fetch_add(chunk);
      if (begin >= mine.size()) break;
      const std::size_t end = std::min(begin + chunk, mine.size());
      for (std::size_t k = begin; k < end; ++k) {
        const DesignSpec d = sweep_candidate(ctx, mine[k]);
        rows[k] =
            sweep_row(ctx, mine[k], d, evaluate_design(ctx.characterisation, ctx.material, d, ws));
      }
      const std::size_t now = done.fetch_add(end - begin) + (end - begin);
      if (progress) progress(now, mine.size());
    }
  };
  const int n = std::max(1, threads);
  std::vector<std::thread> pool;
  for (int t = 1; t < n; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  return rows;
}

void rank_rows(std::vector<std::string>& rows, const std::string& objective, bool maximize) {
  const int obj = column_index(objective), feas = column_index("feasible");
  struct Key {
    int feasible;
    double value;
    long long index;
  };
  std::vector<std::pair<Key, std::string>> keyed;
  keyed.reserve(rows.size());
  for (auto& r : rows) {
    keyed.emplace_back(
        Key{field(r, feas) == "1" ? 1 : 0, number(field(r, obj)), std::stoll(field(r, 0))},
        std::move(r));
  }
  std::stable_sort(keyed.begin(), keyed.end(), [&](const auto& a, const auto& b) {
    if (a.first.feasible != b.first.feasible) return a.first.feasible > b.first.feasible;
    if (a.first.value != b.first.value)
      return maximize ? a.first.value > b.first.value : a.first.value < b.first.value;
    return a.first.index < b.first.index;
  });
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = std::move(keyed[i].second);
}

std::string sweep_file(const SweepSpec& spec, const std::string& spec_name,
                       std::vector<std::string> rows, int shard, int shards) {
  rank_rows(rows, spec.objective, spec.maximize);
  std::string out = fmt::format(
      "# scpkit sweep: {}; candidates {}; {} {}; shard {}/{}\n", spec_name, spec.candidate_count(),
      spec.maximize ? "maximize" : "minimize", spec.objective, shard, shards);
  out += sweep_header() + "\n";
  for (const auto& r : rows) out += r + "\n";
  return out;
}

std::string merge_sweep_files(const std::vector<std::filesystem::path>& files) {
  if (files.empty()) throw InputError("merge", 0, 0, "no shard files given");
  std::string first_tag;  // the comment line without the shard part
  int shards = -1;
  std::set<int> seen;
  std::vector<std::string> rows;
  std::string objective;
  bool maximize = true;
  long long candidates = 0;
  for (const auto& f : files) {
    std::istringstream in(read_text_file(f));
    std::string comment, header;
    std::getline(in, comment);
    std::getline(in, header);
    const std::size_t pos = comment.rfind("; shard ");
    if (comment.rfind("# scpkit sweep: ", 0) != 0 || pos == std::string::npos) {
      throw InputError(f.string(), 1, 1, "not an scpkit sweep output (first line)");
    }
    if (header != sweep_header())
      throw InputError(f.string(), 2, 1, "unexpected header: written by another scpkit version?");
    const std::string tag = comment.substr(0, pos);
    int k = -1, n = -1;
    if (std::sscanf(comment.c_str() + pos, "; shard %d/%d", &k, &n) != 2 || k < 0 || n < 1 ||
        k >= n) {
      throw InputError(f.string(), 1, static_cast<int>(pos) + 3, "malformed shard i/N");
    }
    if (first_tag.empty()) {
      first_tag = tag;
      shards = n;
      const std::size_t c = tag.find("; candidates ");
      candidates = std::atoll(tag.c_str() + c + 13);
      const std::size_t o = tag.find("; ", c + 13);
      std::istringstream words(tag.substr(o + 2));
      std::string how;
      words >> how >> objective;
      maximize = how == "maximize";
    } else if (tag != first_tag || n != shards) {
      throw InputError(f.string(), 1, 1, "a shard of another sweep (the first line differs)");
    }
    if (!seen.insert(k).second)
      throw InputError(f.string(), 1, static_cast<int>(pos) + 3,
                       fmt::format("shard {}/{} given twice", k, n));
    std::string line;
    int line_no = 2;
    while (std::getline(in, line)) {
      ++line_no;
      if (line.empty()) continue;
      if (std::count(line.begin(), line.end(), ',') + 1 != static_cast<long>(columns().size())) {
        throw InputError(f.string(), line_no, 1, "wrong number of fields");
      }
      rows.push_back(line);
    }
  }
  if (static_cast<int>(seen.size()) != shards) {
    std::string missing;
    for (int k = 0; k < shards; ++k) {
      if (!seen.count(k)) missing += (missing.empty() ? "" : ", ") + std::to_string(k);
    }
    throw InputError(files.front().string(), 0, 0,
                     fmt::format("shards missing: {} (of {})", missing, shards));
  }
  if (static_cast<long long>(rows.size()) != candidates) {
    throw InputError(files.front().string(), 0, 0,
                     fmt::format("{} rows for {} candidates", rows.size(), candidates));
  }
  rank_rows(rows, objective, maximize);
  std::string out = first_tag + "; shard 0/1\n" + sweep_header() + "\n";
  for (const auto& r : rows) out += r + "\n";
  return out;
}

}  // namespace scpkit
