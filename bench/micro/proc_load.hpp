// The machine's load as the microbenchmarks record it beside their figures.
#pragma once

#include <fstream>
#include <string>

namespace coloc::bench {

/// The first line of /proc/loadavg ("" where it cannot be read).
inline std::string loadavg() {
  std::ifstream f("/proc/loadavg");
  std::string l;
  std::getline(f, l);
  return l;
}

}  // namespace coloc::bench
