// coloc/partition/setup.hpp — the case-file keys of the domain and of the partition, and the
// decomposition they describe.
#pragma once

#include "coloc/core/config.hpp"
#include "coloc/partition/decomposition.hpp"

namespace coloc {

/// domain.{origin,length,cells,periodic}, partition.{strategy,dims}.
void declareDomainConfig(Schema& s);
GlobalGrid gridFromConfig(const Config& cfg);
/// The uniform strategy's decomposition of the case (its process grid: processGridFromConfig).
Decomposition decompositionFromConfig(const Comm& world, const Config& cfg);
/// The thinnest block (cells along an axis) the case's physics accept: 2 (the fluid's ghost
/// layers) unless run.mode is particles.
int minBlockCells(const Config& cfg);
/// The uniform strategy's process grid for `ranks` ranks (partition.dims, domain.cells, run.mode);
/// no communication.
Int3 processGridFromConfig(const Config& cfg, int ranks);

}  // namespace coloc
