#include "coloc/coupling/heat_transfer.hpp"

#include <fmt/format.h>

#include <cmath>

#include "coloc/core/error.hpp"

namespace coloc::coupling {

HeatLaw heatLawFromName(const std::string& name) {
  if (name == "none") return HeatLaw::None;
  if (name == "ranz_marshall") return HeatLaw::RanzMarshall;
  if (name == "gunn") return HeatLaw::Gunn;
  throw ConfigError("coupling.heat_transfer",
                    fmt::format("unknown law '{}' (none, ranz_marshall, gunn)", name));
}

const char* heatLawName(HeatLaw law) {
  switch (law) {
    case HeatLaw::RanzMarshall:
      return "ranz_marshall";
    case HeatLaw::Gunn:
      return "gunn";
    case HeatLaw::None:
      break;
  }
  return "none";
}

HeatLaw heatLawFromConfig(const Config& cfg) {
  const HeatLaw law = heatLawFromName(cfg.string("coupling.heat_transfer"));
  if (law != HeatLaw::None && !(cfg.boolean("fluid.heat") && cfg.boolean("particles.heat")))
    throw ConfigError("coupling.heat_transfer",
                      fmt::format("{} needs fluid.heat = true and particles.heat = true (the "
                                  "fluid's and the particles' temperatures)",
                                  heatLawName(law)));
  return law;
}

double nusselt(HeatLaw law, double eps, double re, double pr) {
  return nusseltPr3(law, eps, re, std::cbrt(pr));
}

}  // namespace coloc::coupling
