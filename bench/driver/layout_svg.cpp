// The layout picture of `coloc check --draw` (layout_svg.hpp).
#include "layout_svg.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "coloc/core/error.hpp"
#include "coloc/core/files.hpp"
#include "coloc/io/xdmf.hpp"

namespace coloc {
namespace {

// matplotlib's tab20, the palette snapshot.py colours ranks with: rank r takes entry r % 20.
constexpr const char* kRankColour[20] = {"#1f77b4", "#aec7e8", "#ff7f0e", "#ffbb78", "#2ca02c",
                                         "#98df8a", "#d62728", "#ff9896", "#9467bd", "#c5b0d5",
                                         "#8c564b", "#c49c94", "#e377c2", "#f7b6d2", "#7f7f7f",
                                         "#c7c7c7", "#bcbd22", "#dbdb8d", "#17becf", "#9edae5"};

constexpr double kPanelWidth = 300;  // px for the across axis (the up axis keeps the aspect)
constexpr double kPanelHeightMax = 420;
constexpr double kMargin = 40;     // around each panel: titles above, the axis below
constexpr double kTitle = 44;      // two lines of title
constexpr int kDensityBins = 100;  // at most this many grey cells along each in-plane axis

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}

/// Pixel geometry shared by every panel.
struct Frame {
  double w = 0, h = 0;    // the plane's drawing, px
  double sx = 0, sy = 0;  // px a cell along across / up
  int nx = 0, ny = 0;     // cells along across / up
  bool upIsPlus = true;
  double x(double i) const { return sx * i; }
  double y(double k) const { return upIsPlus ? h - sy * k : sy * k; }  // SVG y grows downwards
};

/// The rectangle of cells [i0, i1) x [k0, k1) of the plane, in the panel's pixels.
void rect(std::ostringstream& o, const Frame& f, double i0, double i1, double k0, double k1) {
  const double ya = f.y(k0), yb = f.y(k1);
  o << "x=\"" << num(f.x(i0)) << "\" y=\"" << num(std::min(ya, yb)) << "\" width=\""
    << num(f.x(i1) - f.x(i0)) << "\" height=\"" << num(std::fabs(yb - ya)) << "\"";
}

}  // namespace

LayoutPlane layoutPlane(const GlobalGrid& g, const Real3& gravity, const std::string& plane) {
  LayoutPlane p;
  int up = -1;
  double gmax = 0;
  for (int a = 0; a < 3; ++a)
    if (std::fabs(gravity[a]) > gmax) {
      gmax = std::fabs(gravity[a]);
      up = a;
    }
  if (!plane.empty()) {
    if (plane != "xz" && plane != "yz" && plane != "xy")
      throw ConfigError("--plane", "'" + plane + "': expected xz, yz or xy (the plane's two axes)");
    const int a = plane[0] - 'x', b = plane[1] - 'x';
    p.normal = 3 - a - b;
    if (up == a || up == b) {  // the vertical axis is in the plane: drawn upwards
      p.up = up;
      p.across = up == a ? b : a;
      p.upIsPlus = gravity[up] < 0;
    } else {
      p.up = b;
      p.across = a;
      p.upIsPlus = true;
    }
    p.slice = g.cells[p.normal] / 2;
    return p;
  }
  if (up < 0) {  // no gravity: the longest axis is vertical
    up = 0;
    for (int a = 1; a < 3; ++a)
      if (g.length[a] > g.length[up]) up = a;
    p.upIsPlus = true;
  } else {
    p.upIsPlus = gravity[up] < 0;
  }
  const int o1 = (up + 1) % 3, o2 = (up + 2) % 3;
  p.up = up;
  p.across = g.length[o1] >= g.length[o2] ? o1 : o2;
  p.normal = 3 - up - p.across;
  p.slice = g.cells[p.normal] / 2;
  return p;
}

void writeLayoutSvg(const std::string& path, const GlobalGrid& g, const LayoutPlane& plane,
                    const std::vector<double>& particlesPerCell,
                    const std::vector<LayoutDrawing>& panels, const std::string& caption) {
  Frame f;
  f.nx = g.cells[plane.across];
  f.ny = g.cells[plane.up];
  f.upIsPlus = plane.upIsPlus;
  const double aspect = g.length[plane.up] / g.length[plane.across];
  f.w = kPanelWidth;
  f.h = kPanelWidth * aspect;
  if (f.h > kPanelHeightMax) {
    f.h = kPanelHeightMax;
    f.w = kPanelHeightMax / aspect;
  }
  f.sx = f.w / f.nx;
  f.sy = f.h / f.ny;
  const int columns = f.h >= f.w ? 4 : 2;
  const int rows = (static_cast<int>(panels.size()) + columns - 1) / columns;
  const double cellW = std::max(f.w, 240.0) + 2 * kMargin, cellH = f.h + kTitle + 2 * kMargin;
  const double width = columns * cellW, height = rows * cellH + 60;

  std::ostringstream o;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" "
    << "width=\"" << num(width) << "\" height=\"" << num(height) << "\" viewBox=\"0 0 "
    << num(width) << " " << num(height) << "\" font-family=\"DejaVu Sans, Arial, sans-serif\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";

  // The particles a cell, summed along the normal and binned to at most kDensityBins a side:
  // drawn once (defs) and used by every panel.
  const int bx = std::min(f.nx, kDensityBins), by = std::min(f.ny, kDensityBins);
  std::vector<double> bins(static_cast<std::size_t>(bx) * by, 0.0);
  if (particlesPerCell.size() == static_cast<std::size_t>(g.cellCount())) {
    for (int k = 0; k < g.cells[2]; ++k)
      for (int j = 0; j < g.cells[1]; ++j)
        for (int i = 0; i < g.cells[0]; ++i) {
          const int c[3] = {i, j, k};
          const int u = static_cast<int>(1LL * c[plane.across] * bx / f.nx);
          const int v = static_cast<int>(1LL * c[plane.up] * by / f.ny);
          bins[static_cast<std::size_t>(u) + static_cast<std::size_t>(bx) * v] +=
              particlesPerCell[static_cast<std::size_t>(i +
                                                        g.cells[0] * (j + 1LL * g.cells[1] * k))];
        }
  }
  const double binMax = *std::max_element(bins.begin(), bins.end());
  o << "<defs><g id=\"density\" shape-rendering=\"crispEdges\">\n";
  if (binMax > 0)
    for (int v = 0; v < by; ++v)
      for (int u = 0; u < bx; ++u) {
        const double n = bins[static_cast<std::size_t>(u) + static_cast<std::size_t>(bx) * v];
        if (n <= 0) continue;
        o << "<rect class=\"density\" ";
        rect(o, f, 1.0 * u * f.nx / bx, 1.0 * (u + 1) * f.nx / bx, 1.0 * v * f.ny / by,
             1.0 * (v + 1) * f.ny / by);
        o << " fill=\"#000\" fill-opacity=\"" << num(0.08 + 0.5 * n / binMax) << "\"/>\n";
      }
  o << "</g></defs>\n";

  const char* names = "xyz";
  const double sliceLo = g.origin[plane.normal] + plane.slice * g.spacing(plane.normal);
  for (std::size_t p = 0; p < panels.size(); ++p) {
    const LayoutDrawing& d = panels[p];
    const double ox = kMargin + static_cast<double>(p % columns) * cellW;
    const double oy = kTitle + static_cast<double>(p / columns) * cellH + 10;
    o << "<g class=\"panel\" data-strategy=\"" << xmlEscape(d.strategy) << "\" data-ranks=\""
      << d.fluid.size() << "\" transform=\"translate(" << num(ox) << "," << num(oy) << ")\">\n";
    o << "<text x=\"0\" y=\"-26\" font-size=\"15\" font-weight=\"bold\">"
      << xmlEscape((d.chosen ? "* " : "") + d.strategy) << "</text>\n"
      << "<text x=\"0\" y=\"-9\" font-size=\"11\">" << xmlEscape(d.summary) << "</text>\n";
    o << "<use xlink:href=\"#density\" href=\"#density\"/>\n";
    // Each rank's fluid block where the plane cuts it.
    for (std::size_t r = 0; r < d.fluid.size(); ++r) {
      const IndexBox& b = d.fluid[r];
      if (plane.slice < b.lo[plane.normal] || plane.slice >= b.hi[plane.normal]) continue;
      const int i0 = b.lo[plane.across], i1 = b.hi[plane.across];
      const int k0 = b.lo[plane.up], k1 = b.hi[plane.up];
      o << "<rect class=\"block\" data-rank=\"" << r << "\" data-lo=\"" << i0 << " " << k0
        << "\" data-hi=\"" << i1 << " " << k1 << "\" ";
      rect(o, f, i0, i1, k0, k1);
      o << " fill=\"" << kRankColour[r % 20] << "\" fill-opacity=\"0.45\" stroke=\"#222\" "
        << "stroke-width=\"1\"/>\n";
      const double w = f.x(i1) - f.x(i0), h = std::fabs(f.y(k1) - f.y(k0));
      const double size = std::min({14.0, 0.45 * w, 0.45 * h});
      if (size >= 5)
        o << "<text x=\"" << num(f.x(0.5 * (i0 + i1))) << "\" y=\""
          << num(0.5 * (f.y(k0) + f.y(k1)) + 0.35 * size) << "\" font-size=\"" << num(size)
          << "\" text-anchor=\"middle\">" << r << "</text>\n";
    }
    // Particle boxes of their own (independent partitions), dashed.
    for (std::size_t r = 0; r < d.particles.size(); ++r) {
      const IndexBox& b = d.particles[r];
      if (r < d.fluid.size() && b.lo == d.fluid[r].lo && b.hi == d.fluid[r].hi) continue;
      if (plane.slice < b.lo[plane.normal] || plane.slice >= b.hi[plane.normal]) continue;
      o << "<rect class=\"dem-block\" data-rank=\"" << r << "\" ";
      rect(o, f, b.lo[plane.across], b.hi[plane.across], b.lo[plane.up], b.hi[plane.up]);
      o << " fill=\"none\" stroke=\"#000\" stroke-width=\"2\" stroke-dasharray=\"6,4\"/>\n";
    }
    // The frame and the axes' extents.
    o << "<rect x=\"0\" y=\"0\" width=\"" << num(f.w) << "\" height=\"" << num(f.h)
      << "\" fill=\"none\" stroke=\"#000\"/>\n";
    const double lo[2] = {g.origin[plane.across], g.origin[plane.up]};
    const double hi[2] = {lo[0] + g.length[plane.across], lo[1] + g.length[plane.up]};
    char t[160];
    std::snprintf(t, sizeof t, "%s: %g .. %g m (%d cells)",
                  std::string(1, names[plane.across]).c_str(), lo[0], hi[0], f.nx);
    o << "<text x=\"0\" y=\"" << num(f.h + 15) << "\" font-size=\"10\">" << xmlEscape(t)
      << "</text>\n";
    std::snprintf(t, sizeof t, "%s: %g .. %g m (%d cells), up %s",
                  std::string(1, names[plane.up]).c_str(), lo[1], hi[1], f.ny,
                  plane.upIsPlus ? "+" : "-");
    o << "<text x=\"0\" y=\"" << num(f.h + 28) << "\" font-size=\"10\">" << xmlEscape(t)
      << "</text>\n";
    o << "</g>\n";
  }
  char where[200];
  std::snprintf(where, sizeof where,
                "The plane %c = %g .. %g m (cell %d of %d): each rank's block it cuts, numbered by "
                "rank; dashed: particle boxes of their own; grey: the particles a cell, summed "
                "along %c.",
                names[plane.normal], sliceLo, sliceLo + g.spacing(plane.normal), plane.slice,
                g.cells[plane.normal], names[plane.normal]);
  o << "<text x=\"10\" y=\"" << num(height - 30) << "\" font-size=\"11\">" << xmlEscape(where)
    << "</text>\n"
    << "<text class=\"stamp\" x=\"10\" y=\"" << num(height - 12) << "\" font-size=\"10\" "
    << "fill=\"#666\">" << xmlEscape(caption) << "</text>\n"
    << "</svg>\n";

  // The path the user named: replaced only when it holds an SVG already, never the case file, a
  // link or a device (coloc/core/files.hpp).
  writeUserFile("--draw", path, o.str(), "<?xml");
}

}  // namespace coloc
