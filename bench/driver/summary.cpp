// The phase table and the figure of merit (summary.hpp).
#include "summary.hpp"

#include <cstdio>

namespace coloc {
namespace {

double number(const Json& j, const char* a, const char* b) {
  if (!j.contains(a) || !j[a].contains(b) || !j[a][b].is_number()) return 0.0;
  return j[a][b].get<double>();
}

std::string row(const char* name, double min, double avg, double max, double wall) {
  char b[160];
  std::snprintf(b, sizeof b, "  %-24s %12.6g %12.6g %12.6g %8.2f", name, min, avg, max,
                wall > 0 ? 100.0 * avg / wall : 0.0);
  return b;
}

}  // namespace

std::vector<std::string> phaseTable(const Json& report) {
  std::vector<std::string> lines;
  const double wall = number(report, "run", "wall_s");
  char b[160];
  std::snprintf(b, sizeof b, "  %-24s %12s %12s %12s %8s", "phase (over ranks)", "min (s)",
                "avg (s)", "max (s)", "% loop");
  lines.push_back(b);
  double sum = 0;
  const Json timers = report.contains("timers") ? report["timers"] : Json::object();
  for (const auto& [name, t] : timers.items()) {
    if (name == "setup") continue;  // before the loop: below
    const double avg = t.value("avg", 0.0);
    sum += avg;
    lines.push_back(row(name.c_str(), t.value("min", 0.0), avg, t.value("max", 0.0), wall));
  }
  std::snprintf(b, sizeof b, "  %-24s %12s %12.6g %12s %8.2f", "phases (sum)", "", sum, "",
                wall > 0 ? 100.0 * sum / wall : 0.0);
  lines.push_back(b);
  std::snprintf(b, sizeof b, "  %-24s %12s %12.6g %12s %8.2f", "other (in no phase)", "",
                wall - sum, "", wall > 0 ? 100.0 * (wall - sum) / wall : 0.0);
  lines.push_back(b);
  std::snprintf(b, sizeof b, "  %-24s %12s %12.6g %12s %8.2f", "loop (run.wall_s)", "", wall, "",
                100.0);
  lines.push_back(b);
  if (timers.contains("setup")) {
    const Json& s = timers["setup"];
    std::snprintf(b, sizeof b, "  %-24s %12.6g %12.6g %12.6g %8s", "setup (before the loop)",
                  s.value("min", 0.0), s.value("avg", 0.0), s.value("max", 0.0), "");
    lines.push_back(b);
  }
  return lines;
}

Json figureOfMerit(const Json& report) {
  long long cores = 0;
  if (report.contains("provenance") && report["provenance"].contains("cores_used"))
    cores = report["provenance"]["cores_used"].get<long long>();
  if (cores <= 0 && report.contains("mpi")) cores = report["mpi"].value("ranks", 1LL);
  if (cores <= 0) cores = 1;
  const double c = static_cast<double>(cores);
  return Json{
      {"particle_steps_per_s_per_core", number(report, "throughput", "particle_steps_per_s") / c},
      {"cell_steps_per_s_per_core", number(report, "throughput", "cell_steps_per_s") / c},
      {"inter_physics_share", number(report, "fractions", "inter_physics")},
      {"cores", cores}};
}

std::string figureOfMeritLine(const Json& f) {
  char b[256];
  std::snprintf(b, sizeof b,
                "coloc: figure of merit: %.4g particle-steps/s/core, %.4g cell-steps/s/core, "
                "inter-physics %.3g%% of the step (%lld core%s)",
                f.value("particle_steps_per_s_per_core", 0.0),
                f.value("cell_steps_per_s_per_core", 0.0),
                100.0 * f.value("inter_physics_share", 0.0), f.value("cores", 0LL),
                f.value("cores", 0LL) == 1 ? "" : "s");
  return b;
}

}  // namespace coloc
