// scpkit: one binary, subcommands. The one place that catches errors and maps them to exit
// codes (docs/cli.md): 0 ok, 1 internal error, 2 usage error, 3 bad input data.
#include <fmt/format.h>

#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "scpkit/memory.hpp"
#include "scpkit/version.hpp"

namespace {

using scpkit::cli::Command;

const std::vector<Command>& commands() {
  static const std::vector<Command> list = {
      {"fit", "identify a hysteresis model from a measurement file", scpkit::cli::run_fit},
      {"predict", "run a model on an input sequence; errors when the response is measured",
       scpkit::cli::run_predict},
      {"invert", "the input sequence that makes a model track a target response",
       scpkit::cli::run_invert},
      {"map", "map a thread model to another ply count and to an SCP actuator",
       scpkit::cli::run_map},
      {"design", "predict one actuator design before it is made", scpkit::cli::run_design},
      {"sweep", "rank many actuator designs (threads, cluster shards)", scpkit::cli::run_sweep},
      {"merge", "join the shards of a sweep into the unsharded result", scpkit::cli::run_merge},
      {"diagnose", "what the model gets wrong, the named cause, the extension's held-out gain",
       scpkit::cli::run_diagnose},
      {"simulate", "synthetic measurements from the virtual test rig", scpkit::cli::run_simulate},
  };
  return list;
}

void print_help() {
  std::cout << "scpkit " << scpkit::kVersion
            << ": hysteresis of supercoiled polymer (SCP) artificial muscles\n\n"
               "usage: scpkit COMMAND [ARGS] [--help]\n\ncommands:\n";
  for (const auto& c : commands()) std::cout << fmt::format("  {:<10} {}\n", c.name, c.summary);
  std::cout
      << "\nscpkit COMMAND --help explains each command. Exit codes: 0 ok, 1 internal error,\n"
         "2 usage error, 3 bad input data (the message names file:line:column).\n"
         "Documentation: docs/cli.md, docs/data-format.md, docs/theory.md.\n";
}

}  // namespace

int main(int argc, char** argv) {
  using namespace scpkit::cli;
  scpkit::keep_large_blocks_in_the_heap();
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    print_help();
    return args.empty() ? kUsageError : kOk;
  }
  if (args[0] == "--version") {
    std::cout << "scpkit " << scpkit::kVersion << "\n";
    return kOk;
  }
  const std::string name = args[0];
  args.erase(args.begin());
  for (const auto& c : commands()) {
    if (name != c.name) continue;
    try {
      return c.run(args);
    } catch (const UsageError& e) {
      std::cerr << "scpkit " << name << ": " << e.what() << "\n(see scpkit " << name
                << " --help)\n";
      return kUsageError;
    } catch (const scpkit::InvalidArgument& e) {  // a library precondition: bad option value
      std::cerr << "scpkit " << name << ": error: " << e.what() << "\n";
      return kUsageError;
    } catch (const scpkit::Error& e) {  // InputError, IdentificationError: the data
      std::cerr << "scpkit " << name << ": error: " << e.what() << "\n";
      return kInputError;
    } catch (const std::exception& e) {
      std::cerr << "scpkit " << name << ": internal error: " << e.what() << "\n";
      return kInternalError;
    }
  }
  std::cerr << "scpkit: unknown command '" << name << "' (see scpkit --help)\n";
  return kUsageError;
}
