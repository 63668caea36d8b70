// Checkpoint file names and options (coloc/io/checkpoint_file.hpp).
#include "coloc/io/checkpoint_file.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>

#include "coloc/core/error.hpp"
#include "coloc/io/output.hpp"

namespace coloc {

CheckpointOptions checkpointOptionsFromConfig(const Config& cfg, const std::string& runOutDir) {
  CheckpointOptions o;
  o.intervalSteps = cfg.integer("output.checkpoint_interval");
  // A build without HDF5 (SimGrid SMPI) has no failure checkpoint to write.
  o.onFailure = cfg.boolean("output.checkpoint_on_failure") && hdf5Available();
  const std::string file = cfg.string("output.checkpoint_file");
  if (const std::string why = checkpointFileProblem(file); !why.empty())
    throw ConfigError("output.checkpoint_file", why);
  const std::string dir = outputOptionsFromConfig(cfg, runOutDir).dir;
  o.path = (std::filesystem::path(dir) / std::filesystem::path(file).lexically_normal()).string();
  return o;
}

namespace {

/// The longest file name (bytes) of the usual file systems (NAME_MAX).
constexpr std::size_t kMaxFileNameBytes = 255;

bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

/// `name` is PREFIX + six or more digits + SUFFIX.
bool stepName(const std::string& name, const std::string& prefix, const std::string& suffix) {
  if (name.size() < prefix.size() + 6 + suffix.size()) return false;
  if (name.compare(0, prefix.size(), prefix) != 0 || !endsWith(name, suffix)) return false;
  for (std::size_t i = prefix.size(); i < name.size() - suffix.size(); ++i)
    if (name[i] < '0' || name[i] > '9') return false;
  return true;
}

}  // namespace

bool matchesStepPattern(const std::string& name, const std::string& pattern) {
  const std::string key = "{step}";
  const auto at = pattern.find(key);
  if (at == std::string::npos) return name == pattern;
  return stepName(name, pattern.substr(0, at), pattern.substr(at + key.size()));
}

std::string runFileRole(const std::string& name) {
  if (name == "report.json") return "the run's report (report.json)";
  if (name == "log.txt") return "the run's log (log.txt)";
  if (name == "plan.csv" || name == "plan.json")
    return "a file of coloc plan (plan.csv, plan.json)";
  if (name.size() > 11 && name.compare(0, 7, "render_") == 0 && endsWith(name, ".png"))
    return "a picture of render.py (render_*.png)";
  if (name == "series.csv") return "the run's time series (series.csv)";
  if (name == "snapshot.png") return "the run's snapshot picture (snapshot.png)";
  if (name == "fields.xmf" || name == "particles.xmf") return "the run's XDMF index (" + name + ")";
  if (stepName(name, "fields_", ".h5") || stepName(name, "particles_", ".h5"))
    return "the run's output file of one step (fields_NNNNNN.h5, particles_NNNNNN.h5)";
  if (name == "rebalance.tmp.h5") return "the run's re-balancing scratch file (rebalance.tmp.h5)";
  if (name == kRunLockFile) return std::string("the output folder's lock (") + kRunLockFile + ")";
  if (endsWith(name, ".tmp")) return "a temporary file of a write in progress (NAME.tmp)";
  const std::filesystem::path p(name);
  if (endsWith(p.stem().string(), ".failed"))
    return "the state of a failed run (NAME.failed.h5, output.checkpoint_on_failure)";
  return "";
}

std::string checkpointFileProblem(const std::string& file) {
  namespace fs = std::filesystem;
  const std::string q = "'" + file + "'";
  if (file.empty()) return "empty file name";
  const fs::path p(file);
  if (p.is_absolute())
    return q +
           " is an absolute path: a checkpoint is written inside the run's output folder "
           "(output.dir, by default the --out folder); give a name relative to it";
  for (const auto& part : p)
    if (part == "..")
      return q +
             " leaves the run's output folder (a '..' part): a checkpoint is written inside it "
             "(output.dir, by default the --out folder)";
  const fs::path normal = p.lexically_normal();
  if (!normal.has_filename() || normal.filename() == "." || file.back() == '/')
    return q + " names a folder, not a file";
  // The name with {step} as a step: what the run's own files would be called at that step.
  std::string name = normal.filename().string();
  const auto at = name.find("{step}");
  if (file.find("{step}") != std::string::npos && at == std::string::npos)
    return q + " has {step} in a folder's name: only the file's name may hold it";
  if (at != std::string::npos && name.find("{step}", at + 1) != std::string::npos)
    return q + " has {step} twice: give it once (it becomes the step, e.g. ck_{step}.h5)";
  // The longest name the run writes from it: the largest step (19 digits), the failed state's
  // ".failed" and the ".tmp" of the write; a file system takes 255 bytes a name.
  {
    std::string longest = name;
    if (at != std::string::npos) longest.replace(at, 6, std::string(19, '0'));
    longest = fs::path(failedCheckpointPath(longest)).filename().string() + ".tmp";
    if (longest.size() > kMaxFileNameBytes)
      return fmt::format(
          "{} is a name of {} bytes: with the step, '.failed' and '.tmp' the run "
          "would write names of up to {} bytes, and a file system takes {}",
          q, name.size(), longest.size(), kMaxFileNameBytes);
  }
  if (at != std::string::npos) name.replace(at, 6, "000000");
  if (const std::string role = runFileRole(name); !role.empty())
    return q + " is the name of " + role +
           ", which the run writes or removes itself: choose another name (e.g. checkpoint.h5, "
           "ck_{step}.h5)";
  return "";
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
