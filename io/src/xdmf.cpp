// The XDMF index of an output series (coloc/io/xdmf.hpp).
#include "coloc/io/xdmf.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "coloc/core/error.hpp"
#include "coloc/core/files.hpp"
#include "io_reason.hpp"

namespace coloc {
namespace {

using h5::ioReason;

// ---- XDMF ---------------------------------------------------------------------------------------

// Shortest text that reads back as exactly v (0.005, not 0.0050000000000000001).
std::string num(double v) {
  char b[32];
  const auto r = std::to_chars(b, b + sizeof b, v);
  return std::string(b, r.ptr);
}

// A time as ParaView's time controls should show it: 12 significant digits, so that the round-off
// of a time summed step by step goes (0.1, not 0.10000000000000007; 1.25, not 1.2499999999999731).
// Steps closer than 1e-12 of the time apart would share a label, far below any dt coloc takes.
// The HDF5 files keep the exact time (their "time" attribute).
std::string timeText(double t) {
  char b[32];
  std::snprintf(b, sizeof b, "%.12g", t);
  return b;
}

}  // namespace

std::string xmlEscape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      case '\'':
        o += "&apos;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

// ---- XDMF ---------------------------------------------------------------------------------------

XdmfSeries XdmfSeries::cells(std::string name, const GlobalGrid& grid) {
  XdmfSeries s;
  s.name_ = std::move(name);
  s.grid_ = grid;
  return s;
}

XdmfSeries XdmfSeries::particles(std::string name) {
  XdmfSeries s;
  s.name_ = std::move(name);
  s.particles_ = true;
  return s;
}

void XdmfSeries::add(XdmfStep s) {
  std::erase_if(steps_, [&](const XdmfStep& o) { return o.step >= s.step; });
  steps_.push_back(std::move(s));
}

std::string XdmfSeries::xml() const {
  std::ostringstream o;
  const auto& g = grid_;
  const std::string cellDims = std::to_string(g.cells[2]) + " " + std::to_string(g.cells[1]) + " " +
                               std::to_string(g.cells[0]);
  o << "<?xml version=\"1.0\" ?>\n"
    << "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    << "<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n"
    << " <Domain>\n"
    << "  <Grid Name=\"" << xmlEscape(name_)
    << "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const auto& s : steps_) {
    const std::string n = std::to_string(s.count);
    auto dataItem = [&](const std::string& dims, const std::string& type, int precision,
                        const std::string& dataset) {
      o << "     <DataItem Dimensions=\"" << dims << "\" NumberType=\"" << type << "\" Precision=\""
        << precision << "\" Format=\"HDF\">" << xmlEscape(s.file) << ":" << xmlEscape(dataset)
        << "</DataItem>\n";
    };
    o << "   <Grid Name=\"" << xmlEscape(name_) << "_" << s.step << "\" GridType=\"Uniform\">\n"
      << "    <Time Value=\"" << timeText(s.time) << "\"/>\n";
    if (particles_) {
      // N one-point cells. The explicit connectivity matters: without it the Xdmf3 readers
      // (ParaView's default) make the N points but no cells, and Surface shows nothing.
      o << "    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n
        << "\" NodesPerElement=\"1\">\n";
      dataItem(n + " 1", "Int", 8, s.connectivity);
      o << "    </Topology>\n"
        << "    <Geometry GeometryType=\"XYZ\">\n";
      dataItem(n + " 3", "Float", 8, s.geometry);
      o << "    </Geometry>\n";
    } else {
      o << "    <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << g.cells[2] + 1 << " "
        << g.cells[1] + 1 << " " << g.cells[0] + 1 << "\"/>\n"
        << "    <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
        << "     <DataItem Name=\"Origin\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" "
           "Format=\"XML\">"
        << num(g.origin[2]) << " " << num(g.origin[1]) << " " << num(g.origin[0]) << "</DataItem>\n"
        << "     <DataItem Name=\"Spacing\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" "
           "Format=\"XML\">"
        << num(g.spacing(2)) << " " << num(g.spacing(1)) << " " << num(g.spacing(0))
        << "</DataItem>\n"
        << "    </Geometry>\n";
    }
    for (const auto& a : s.attributes) {
      const std::string base = particles_ ? n : cellDims;
      o << "    <Attribute Name=\"" << xmlEscape(a.name) << "\" AttributeType=\""
        << (a.vector ? "Vector" : "Scalar") << "\" Center=\"" << (particles_ ? "Node" : "Cell")
        << "\">\n";
      dataItem(a.vector ? base + " 3" : base, a.numberType, a.precision, a.dataset);
      o << "    </Attribute>\n";
    }
    o << "   </Grid>\n";
  }
  o << "  </Grid>\n </Domain>\n</Xdmf>\n";
  return o.str();
}

void XdmfSeries::write(const Comm& comm, const std::string& path) const {
  std::string err;
  if (comm.isRoot()) {
    // PATH.tmp made afresh and renamed over a regular file only (coloc/core/files.hpp)
    try {
      writeFileWhole(path, xml());
    } catch (const std::exception& e) {
      err = e.what();
    }
  }
  if (const std::string msg = comm.firstError(err, 4); !msg.empty()) throw IoError(msg);
}

}  // namespace coloc
