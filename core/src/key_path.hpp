// core/src/key_path.hpp — dotted key paths of the case file ("fluid.solver.tol"): joined and
// split the same way by the schema (schema.cpp) and the reader (config.cpp).
#pragma once

#include <string>
#include <vector>

namespace coloc::detail {

inline std::string joinKey(const std::string& prefix, const std::string& key) {
  return prefix.empty() ? key : prefix + "." + key;
}

inline std::vector<std::string> splitKey(const std::string& path) {
  std::vector<std::string> parts;
  std::string cur;
  for (char c : path) {
    if (c == '.') {
      parts.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  parts.push_back(cur);
  return parts;
}

}  // namespace coloc::detail
