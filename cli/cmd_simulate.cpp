// scpkit simulate RIG.toml: synthetic measurements from the virtual test rig.
#include <fmt/format.h>

#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "scpkit/io/atomic_file.hpp"
#include "scpkit/mechanics/material.hpp"
#include "scpkit/rig/rig.hpp"

namespace scpkit::cli {
namespace {

constexpr const char* kUsage = "scpkit simulate RIG.toml [-o OUT.csv] [--seed N] [--json]";
constexpr const char* kAbout =
    "Runs the virtual test rig described in RIG.toml (docs/rig.md): a ground-truth thread\n"
    "material from its card, a ply count and coil, a load protocol (damped oscillation plus\n"
    "minor loops, paper 002), a displacement sensor (resolution, noise) and optional effects\n"
    "(creep, drift, lonely_stroke, outliers, minor_loop_noncongruence) with magnitudes.\n"
    "Writes a measurement file in the SPEC format, the truth in its metadata, to OUT.csv\n"
    "or to stdout.";

}  // namespace

int run_simulate(const std::vector<std::string>& args) {
  po::options_description opt("options");
  opt.add_options()("help,h", "show this help")("output,o", po::value<std::string>(),
                                                "CSV to write")("seed", po::value<long long>(),
                                                                "override the spec's seed")(
      "json", "print a JSON summary on stdout (requires -o)");
  po::variables_map vm;
  if (!parse_command_line(args, kUsage, kAbout, opt, {"RIG"}, vm)) return kOk;
  RigSpec spec = load_rig_spec(vm["RIG"].as<std::string>());
  if (vm.count("seed")) {
    if (vm["seed"].as<long long>() < 0) throw UsageError("--seed must be >= 0");
    spec.seed = static_cast<std::uint64_t>(vm["seed"].as<long long>());
  }
  if (vm.count("json") && !vm.count("output"))
    throw UsageError("--json needs -o (stdout holds the JSON)");
  const Material material = find_material(spec.material);
  const RigRun run = run_rig(spec, material);
  const std::string csv = run.to_csv();
  if (vm.count("output")) {
    write_file_atomically(vm["output"].as<std::string>(), csv);
    if (vm.count("json")) {
      print_json({{"output_file", vm["output"].as<std::string>()},
                  {"rows", run.rows.size()},
                  {"truth_gain", run.true_gain},
                  {"metadata", run.metadata}});
    } else {
      std::cout << fmt::format("{} readings written to {}\n", run.rows.size(),
                               vm["output"].as<std::string>());
    }
  } else {
    std::cout << csv;
  }
  return kOk;
}

}  // namespace scpkit::cli
