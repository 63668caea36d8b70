// coloc/partition/setup.hpp — the case-file keys of the domain and of the partition, and the
// decomposition they describe.
#pragma once

#include "coloc/core/config.hpp"
#include "coloc/partition/decomposition.hpp"

namespace coloc {

/// domain.{origin,length,cells,periodic}, partition.{strategy,dims}.
void declareDomainConfig(Schema& s);
GlobalGrid gridFromConfig(const Config& cfg);
/// The decomposition of the case (uniform strategy; others come with their own issue).
Decomposition decompositionFromConfig(const Comm& world, const Config& cfg);

}  // namespace coloc
