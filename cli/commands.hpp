#pragma once
#include <string>
#include <vector>

namespace scpkit::cli {

int run_fit(const std::vector<std::string>& args);
int run_predict(const std::vector<std::string>& args);
int run_map(const std::vector<std::string>& args);
int run_simulate(const std::vector<std::string>& args);
int run_invert(const std::vector<std::string>& args);
int run_design(const std::vector<std::string>& args);
int run_sweep(const std::vector<std::string>& args);
int run_merge(const std::vector<std::string>& args);
int run_diagnose(const std::vector<std::string>& args);

}  // namespace scpkit::cli
