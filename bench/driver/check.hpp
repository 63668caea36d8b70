// `coloc check` and `coloc keys PREFIX` (bench/driver/check.cpp, docs/case-files.md).
#pragma once

#include <string>
#include <vector>

namespace coloc {

struct CheckOptions {
  std::string casePath;
  std::vector<std::string> overrides;
  int ranks = 1;            // the rank count to lay the case out for
  bool verbose = false;     // --cuts: print every strategy's cuts
  std::string drawPath;     // --draw FILE.svg: the layouts drawn (layout_svg.hpp)
  std::string plane;        // --plane xz|yz|xy: the plane drawn ("": the vertical mid-plane)
  std::string commandLine;  // for the picture's provenance line
};

/// Validate the case and print, for `ranks` ranks, the layout each partition strategy would
/// choose (cells and particles a rank), the memory estimate and the time-step limits, in this
/// one process; nothing runs. Returns 0 (valid) or 2 (a run would be refused); throws
/// coloc::Error for invalid input.
int checkCase(const CheckOptions& opts);

/// The keys whose path starts with `prefix` (a section, e.g. "particles.sources", or one key);
/// throws ConfigError when none does. Empty prefix: all of them.
std::string describeKeys(const std::string& prefix);

}  // namespace coloc
