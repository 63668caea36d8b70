// The `coloc plan` job: the blocks each strategy would choose for rank counts that are not run,
// and the work and exchange traffic of each rank per step (coupling/plan.hpp), in one process
// (no MPI job). Writes DIR/plan.json, DIR/plan.csv and a summary table on stdout.
#pragma once

#include <string>
#include <vector>

namespace coloc {

struct PlanOptions {
  std::string casePath;
  std::vector<std::string> overrides;
  std::vector<std::string> strategies;  // empty: all
  std::string ranks;                    // "28,56,1024"
  std::string outDir;
};

std::vector<int> parseRankList(const std::string& s);
int planCase(const PlanOptions& opts);

}  // namespace coloc
