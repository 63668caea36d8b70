// Checkpoint file names and options (coloc/io/checkpoint_file.hpp).
#include "coloc/io/checkpoint_file.hpp"

#include <cstdio>
#include <filesystem>

#include "coloc/core/error.hpp"
#include "coloc/io/output.hpp"

namespace coloc {

CheckpointOptions checkpointOptionsFromConfig(const Config& cfg, const std::string& runOutDir) {
  CheckpointOptions o;
  o.intervalSteps = cfg.integer("output.checkpoint_interval");
  o.onFailure = cfg.boolean("output.checkpoint_on_failure");
  const std::filesystem::path file = cfg.string("output.checkpoint_file");
  if (file.empty()) throw ConfigError("output.checkpoint_file", "empty file name");
  const std::string dir = outputOptionsFromConfig(cfg, runOutDir).dir;
  o.path = file.is_absolute() ? file.string() : (std::filesystem::path(dir) / file).string();
  return o;
}

std::string CheckpointOptions::pathAt(long long step) const {
  const std::string key = "{step}";
  const auto at = path.find(key);
  if (at == std::string::npos) return path;
  char b[32];
  std::snprintf(b, sizeof b, "%06lld", step);
  return path.substr(0, at) + b + path.substr(at + key.size());
}

std::string failedCheckpointPath(const std::string& path) {
  std::filesystem::path p(path);
  const std::string ext = p.extension().string();
  return (p.parent_path() / (p.stem().string() + ".failed" + (ext.empty() ? ".h5" : ext))).string();
}

}  // namespace coloc
