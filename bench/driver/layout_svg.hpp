// `coloc check --draw FILE.svg`: a picture of the layout each partition strategy chooses (the
// blocks or tiled boxes on the plane that holds the vertical axis, numbered by rank, over the
// particles a cell), written as SVG by the driver itself (no script, no fork from an MPI rank).
#pragma once

#include <string>
#include <vector>

#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/field.hpp"

namespace coloc {

/// One panel: a strategy's layout.
struct LayoutDrawing {
  std::string strategy;
  std::string summary;              // one line under the title (shapes, imbalance; or why not)
  std::vector<IndexBox> fluid;      // rank r's fluid block (empty: the strategy cannot)
  std::vector<IndexBox> particles;  // rank r's particle box; drawn dashed where it differs
  bool chosen = false;              // the case's partition.strategy
};

/// The plane drawn: the vertical axis (gravity's, else the longest), the longer of the other two
/// across, cut at the middle cell of the third (as bench/scripts/snapshot.py).
struct LayoutPlane {
  int up = 2, across = 0, normal = 1;
  bool upIsPlus = true;  // up points along +axis `up`
  int slice = 0;         // the cell index along `normal` the plane cuts
};
/// `plane` "" chooses as above; "xz", "yz" or "xy" names the two axes in the plane (cut at the
/// middle cell of the third): the vertical one drawn upwards when it is one of them, else the
/// second named (y of xy) upwards and the first across. Throws ConfigError naming --plane for
/// another value.
LayoutPlane layoutPlane(const GlobalGrid& g, const Real3& gravity, const std::string& plane = "");

/// Writes the SVG to `path` (through path.tmp and a rename: never a partial file). Grey: the
/// particles a cell (`particlesPerCell`, x fastest) summed along the normal; each rank's block
/// cut by the plane filled in its colour and numbered; particle boxes that differ from the fluid
/// blocks (independent partitions) dashed. `caption`: the command and its provenance, drawn at
/// the bottom. Throws IoError naming the file.
void writeLayoutSvg(const std::string& path, const GlobalGrid& g, const LayoutPlane& plane,
                    const std::vector<double>& particlesPerCell,
                    const std::vector<LayoutDrawing>& panels, const std::string& caption);

}  // namespace coloc
