// What a restart keeps from its checkpoint and what it takes from the case (restart_account.hpp).
#include "restart_account.hpp"

#include <fmt/format.h>

#include <utility>
#include <vector>

#include "coloc/core/error.hpp"
#include "coloc/coupling/checkpoint.hpp"

namespace coloc {

namespace {

using Differences = std::vector<std::pair<std::string, std::pair<Json, Json>>>;

/// The keys whose values differ between two resolved configurations: dotted paths (list entries
/// by index), each with both values; a list of numbers is one value.
void diffConfig(const Json& a, const Json& b, const std::string& path, Differences& out) {
  const auto objectLike = [](const Json& j) {
    return j.is_object() || (j.is_array() && !j.empty() && j.front().is_object());
  };
  if (objectLike(a) && objectLike(b) && a.type() == b.type()) {
    if (a.is_array() && a.size() != b.size()) {
      out.push_back({path, {Json(a.size()), Json(b.size())}});
      return;
    }
    if (a.is_array()) {
      for (std::size_t i = 0; i < a.size(); ++i)
        diffConfig(a[i], b[i], fmt::format("{}.{}", path, i), out);
      return;
    }
    for (const auto& [k, v] : a.items())
      diffConfig(v, b.contains(k) ? b[k] : Json(), path.empty() ? k : path + "." + k, out);
    for (const auto& [k, v] : b.items())
      if (!a.contains(k)) diffConfig(Json(), v, path.empty() ? k : path + "." + k, out);
    return;
  }
  if (a != b) out.push_back({path, {a, b}});
}

/// What a restart keeps from its checkpoint although the case gives another value: what is
/// baked into the state (the particles: their sources, radii and masses, i.e. the materials'
/// density; the fluid's initial condition: velocity and temperature). Every other key is taken
/// from the case.
bool keptFromCheckpoint(const std::string& key) {
  const auto under = [&](const char* p) {
    const std::string s(p);
    return key == s || key.rfind(s + ".", 0) == 0;
  };
  if (under("particles.sources") || under("particles.seed") || under("fluid.initial_velocity") ||
      under("fluid.initial_temperature"))
    return true;
  return key.rfind("particles.materials.", 0) == 0 && key.ends_with(".density");
}

}  // namespace

Json accountRestart(const Comm& world, const std::string& checkpoint, const Config& cfg,
                    RunLog& log) {
  const coupling::CheckpointInfo info = coupling::readCheckpointInfo(world, checkpoint);
  Json stored;
  try {
    stored = Json::parse(info.config);
  } catch (const std::exception&) {
    stored = Json::object();
  }
  Differences diff;
  diffConfig(stored, cfg.json(), "", diff);
  Json kept = Json::object(), taken = Json::object();
  std::string keptText, takenText;
  for (const auto& [key, values] : diff) {
    if (key == "description" || key == "name") continue;
    const bool keep = keptFromCheckpoint(key);
    (keep ? kept : taken)[key] = {{"checkpoint", values.first}, {"case", values.second}};
    std::string& text = keep ? keptText : takenText;
    if (!text.empty()) text += ", ";
    text += key + " (" + values.first.dump() + " -> " + values.second.dump() + ")";
  }
  const Json report = {{"checkpoint", checkpoint},
                       {"step", info.steps},
                       {"time", info.time},
                       {"kept_from_checkpoint", kept},
                       {"taken_from_case", taken}};
  if (world.isRoot() && !diff.empty()) {
    if (!keptText.empty())
      log.out(
          "coloc: note: restart: kept from the checkpoint (in its particles and fields), "
          "not the case's values: {}\n",
          keptText);
    if (!takenText.empty())
      log.out("coloc: note: restart: taken from the case (checkpoint -> case): {}\n", takenText);
  }
  return report;
}

void refuseEmptyRestart(const Config& cfg, const std::string& checkpoint, long long steps,
                        double time) {
  // A restart at or past the end runs nothing: refused rather than an empty success.
  const long long runSteps = cfg.integer("run.steps");
  const double endTime = cfg.number("run.end_time");
  if (runSteps > 0 && steps >= runSteps)
    throw ConfigError("run.steps",
                      fmt::format("{}: the checkpoint {} is at step {} already, nothing to run "
                                  "(run.steps counts from the initial condition: give more steps)",
                                  runSteps, checkpoint, steps));
  if (runSteps == 0 && time >= endTime * (1.0 - 1e-12)) {
    throw ConfigError("run.end_time",
                      fmt::format("{:.9g} s: the checkpoint is at t = {:.9g} s ({}) already, "
                                  "nothing to run (give a later end)",
                                  endTime, time, checkpoint));
  }
}

}  // namespace coloc
