// scpkit sweep SWEEP.toml and scpkit merge SHARDS...: batch design sweeps.
#include <fmt/format.h>
#include <unistd.h>

#include <cstdlib>
#include <iostream>
#include <mutex>

#include "commands.hpp"
#include "common.hpp"
#include "scpkit/design/sweep.hpp"
#include "scpkit/io/atomic_file.hpp"

namespace scpkit::cli {
namespace {

constexpr const char* kUsage =
    "scpkit sweep SWEEP.toml -o OUT.csv [--threads N] [--shard i/N] [--json]";
constexpr const char* kAbout =
    "Evaluates a grid and/or seeded random samples of actuator designs (docs/design.md): one CSV\n"
    "row per candidate with every figure, ranked (feasible first, then by the objective), with\n"
    "the reason a candidate is infeasible. The output is byte-identical for any --threads.\n"
    "--shard i/N evaluates candidates i, i+N, ... (default from SLURM_ARRAY_TASK_ID and\n"
    "SLURM_ARRAY_TASK_COUNT when set); `scpkit merge` joins the shards into exactly the\n"
    "unsharded result. A progress bar goes to stderr when it is a terminal.";
constexpr const char* kMergeUsage = "scpkit merge SHARD.csv... -o OUT.csv";

std::pair<int, int> parse_shard(const std::string& s) {
  int k = -1, n = -1;
  char slash = 0;
  std::istringstream in(s);
  if (!(in >> k >> slash >> n) || slash != '/' || n < 1 || k < 0 || k >= n || !in.eof()) {
    throw UsageError(fmt::format("--shard must be i/N with 0 <= i < N, got '{}'", s));
  }
  return {k, n};
}

}  // namespace

int run_sweep(const std::vector<std::string>& args) {
  po::options_description opt("options");
  opt.add_options()("help,h", "show this help")("output,o", po::value<std::string>(),
                                                "CSV to write (required)")(
      "shard", po::value<std::string>(), "evaluate shard i of N (i/N)")(
      "json", "print a JSON summary on stdout");
  add_threads_option(opt, "worker threads");
  po::variables_map vm;
  if (!parse_command_line(args, kUsage, kAbout, opt, {"SWEEP"}, vm)) return kOk;
  if (!vm.count("output")) throw UsageError("-o OUT.csv is required");
  const int threads = threads_from(vm);
  int shard = 0, shards = 1;
  if (vm.count("shard")) {
    std::tie(shard, shards) = parse_shard(vm["shard"].as<std::string>());
  } else if (const char* id = std::getenv("SLURM_ARRAY_TASK_ID")) {
    const char* count = std::getenv("SLURM_ARRAY_TASK_COUNT");
    if (!count) throw UsageError("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not");
    std::tie(shard, shards) = parse_shard(std::string(id) + "/" + count);
  }
  const std::filesystem::path path = vm["SWEEP"].as<std::string>();
  const SweepSpec spec = load_sweep_spec(path);
  const SweepContext ctx = prepare_sweep(spec);

  const bool bar = ::isatty(STDERR_FILENO) && !vm.count("json");
  std::mutex m;
  int last = -1;
  auto progress = [&](std::size_t done, std::size_t total) {
    if (!bar) return;
    const int pct = static_cast<int>(100 * done / std::max<std::size_t>(total, 1));
    std::lock_guard lock(m);
    if (pct == last) return;
    last = pct;
    const int w = 40 * pct / 100;
    std::cerr << "\r[" << std::string(w, '#') << std::string(40 - w, ' ') << "] " << pct << " % ("
              << done << "/" << total << ")" << std::flush;
  };
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::string> rows = run_sweep(ctx, shard, shards, threads, progress);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (bar) std::cerr << "\n";
  const std::size_t evaluated = rows.size();
  std::size_t feasible = 0;
  const std::string out =
      sweep_file(spec, path.filename().string(), std::move(rows), shard, shards);
  write_file_atomically(vm["output"].as<std::string>(), out);
  // Count feasible rows and keep the best one for the report.
  std::istringstream in(out);
  std::string line, best;
  std::getline(in, line);
  std::getline(in, line);
  while (std::getline(in, line)) {
    const std::size_t a = line.rfind(',');
    const std::size_t b = line.rfind(',', a - 1);
    if (line.substr(b + 1, a - b - 1) == "1") {
      if (best.empty()) best = line;
      ++feasible;
    }
  }
  if (vm.count("json")) {
    print_json({{"output_file", vm["output"].as<std::string>()},
                {"candidates", spec.candidate_count()},
                {"evaluated", evaluated},
                {"feasible", feasible},
                {"shard", fmt::format("{}/{}", shard, shards)},
                {"threads", threads},
                {"seconds", seconds},
                {"best", best}});
  } else {
    std::cout << fmt::format(
        "{} of {} candidates evaluated (shard {}/{}, {} threads, {:.2f} s), {} feasible; written "
        "to {}\n",
        evaluated, spec.candidate_count(), shard, shards, threads, seconds, feasible,
        vm["output"].as<std::string>());
    if (!best.empty())
      std::cout << "best (" << (spec.maximize ? "max " : "min ") << spec.objective << "): " << best
                << "\n";
  }
  return kOk;
}

int run_merge(const std::vector<std::string>& args) {
  po::options_description opt("options");
  opt.add_options()("help,h", "show this help")("output,o", po::value<std::string>(),
                                                "CSV to write (required)")(
      "shards", po::value<std::vector<std::string>>()->multitoken(), "shard files");
  po::positional_options_description pos;
  pos.add("shards", -1);
  po::variables_map vm;
  try {
    po::store(po::command_line_parser(args).options(opt).positional(pos).run(), vm);
    po::notify(vm);
  } catch (const po::error& e) {
    throw UsageError(e.what());
  }
  if (vm.count("help")) {
    std::cout << "usage: " << kMergeUsage
              << "\n\nJoins the shard outputs of `scpkit sweep --shard i/N` into exactly the\n"
                 "unsharded result; refuses missing, repeated or foreign shards.\n\n"
              << opt << "\n";
    return kOk;
  }
  if (!vm.count("output")) throw UsageError("-o OUT.csv is required");
  if (!vm.count("shards"))
    throw UsageError(std::string("no shard files (usage: ") + kMergeUsage + ")");
  std::vector<std::filesystem::path> files;
  for (const auto& f : vm["shards"].as<std::vector<std::string>>()) files.emplace_back(f);
  write_file_atomically(vm["output"].as<std::string>(), merge_sweep_files(files));
  std::cout << files.size() << " shards merged into " << vm["output"].as<std::string>() << "\n";
  return kOk;
}

}  // namespace scpkit::cli
