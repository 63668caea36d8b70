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
  const double pr3 = std::cbrt(pr);
  switch (law) {
    case HeatLaw::RanzMarshall:
      return 2.0 + 0.6 * std::sqrt(re) * pr3;
    case HeatLaw::Gunn:
      return (7.0 - 10.0 * eps + 5.0 * eps * eps) * (1.0 + 0.7 * std::pow(re, 0.2) * pr3) +
             (1.33 - 2.4 * eps + 1.2 * eps * eps) * std::pow(re, 0.7) * pr3;
    case HeatLaw::None:
      break;
  }
  return 0.0;
}

}  // namespace coloc::coupling
