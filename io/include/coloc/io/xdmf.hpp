// coloc/io/xdmf.hpp — the XDMF index of an output series: one .xmf per series, a temporal
// collection of every output, which lets ParaView open the series of HDF5 files
// (coloc/io/h5io.hpp) as one data set (docs/output.md).
#pragma once

#include <string>
#include <vector>

#include "coloc/core/comm.hpp"
#include "coloc/partition/decomposition.hpp"

namespace coloc {

/// `s` as XML text or attribute value: & < > " ' as entities.
std::string xmlEscape(const std::string& s);

struct XdmfAttribute {
  std::string name;
  bool vector = false;               // 3 components (last dataset axis)
  std::string dataset;               // path inside the step's file, e.g. "/p"
  std::string numberType = "Float";  // Float | Int
  int precision = 8;                 // bytes
};

struct XdmfStep {
  double time = 0;
  long long step = 0;
  std::string file;      // HDF5 file, relative to the .xmf
  long long count = 0;   // particles of this step (particle series)
  std::string geometry;  // dataset of the [N][3] positions (particle series)
  std::vector<XdmfAttribute> attributes;
  std::string connectivity;  // dataset of the [N] vertex indices 0..N-1 (particle series)
};

class XdmfSeries {
 public:
  /// Cell data on the grid: 3DCoRectMesh, Center="Cell".
  static XdmfSeries cells(std::string name, const GlobalGrid& grid);
  /// Particles: Polyvertex topology of N one-point cells (explicit connectivity), XYZ geometry,
  /// Center="Node".
  static XdmfSeries particles(std::string name);

  /// Append a step; entries with step >= s.step are dropped first (a rewritten or restarted
  /// series stays ordered in time).
  void add(XdmfStep s);
  const std::vector<XdmfStep>& steps() const { return steps_; }
  std::string xml() const;
  /// Rank 0 writes `path` (through path.tmp and a rename). Collective: errors on every rank.
  void write(const Comm& comm, const std::string& path) const;

 private:
  std::string name_;
  bool particles_ = false;
  GlobalGrid grid_;
  std::vector<XdmfStep> steps_;
};

}  // namespace coloc
