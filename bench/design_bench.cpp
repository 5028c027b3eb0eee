// Design sweep throughput: designs per second with a 100-step load protocol (target in
// SPEC.md: >= 250 000 per second on 2 cores, the same results for any thread count).
#include <benchmark/benchmark.h>

#include <filesystem>

#include "scpkit/design/sweep.hpp"

namespace {

using namespace scpkit;

const SweepContext& context() {
  static const SweepContext ctx = [] {
    SweepSpec spec = load_sweep_spec(std::filesystem::path(SCPKIT_SOURCE_DIR) / "examples" /
                                     "design" / "bicep-sweep.toml");
    spec.voltage_model.clear();  // load side only: the figure the target is about
    spec.random_samples = 200000;
    spec.grid = false;
    spec.protocol_steps = 100;
    return prepare_sweep(spec);
  }();
  return ctx;
}

void BM_SweepDesigns(benchmark::State& state) {
  const SweepContext& ctx = context();
  const int threads = static_cast<int>(state.range(0));
  std::size_t designs = 0;
  for ([[maybe_unused]] auto _ : state) {
    const auto rows = run_sweep(ctx, 0, 1, threads);
    designs += rows.size();
    benchmark::DoNotOptimize(rows.data());
  }
  state.counters["designs_per_s"] =
      benchmark::Counter(static_cast<double>(designs), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SweepDesigns)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// One design evaluation alone (no formatting), one core.
void BM_EvaluateDesign(benchmark::State& state) {
  const SweepContext& ctx = context();
  DesignWorkspace ws;
  std::size_t i = 0;
  for ([[maybe_unused]] auto _ : state) {
    const DesignSpec d = sweep_candidate(ctx, i++ % 200000);
    benchmark::DoNotOptimize(evaluate_design(ctx.characterisation, ctx.material, d, ws).stroke_mm);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EvaluateDesign);

}  // namespace

BENCHMARK_MAIN();
