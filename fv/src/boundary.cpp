#include "boundary.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace coloc::fv {

namespace {
const char* kAxis[3] = {"x", "y", "z"};
const char* kFace[3][2] = {{"xlo", "xhi"}, {"ylo", "yhi"}, {"zlo", "zhi"}};

/// Loop over the whole allocated range except along axis b, where only `layer` is visited;
/// fn(dst, src) gets flat indices of the ghost and of the corresponding inner value.
template <class F>
void forLayer(Field3<double>& f, int b, int layer, int srcLayer, F&& fn) {
  IndexBox box = f.allocated();
  box.lo[b] = layer;
  box.hi[b] = layer + 1;
  const std::ptrdiff_t stride = f.stride(b);
  const std::ptrdiff_t shift = static_cast<std::ptrdiff_t>(srcLayer - layer) * stride;
  double* p = f.data().data();
  for (int k = box.lo[2]; k < box.hi[2]; ++k)
    for (int j = box.lo[1]; j < box.hi[1]; ++j) {
      const std::ptrdiff_t base = f.index(box.lo[0], j, k);
      for (int i = 0; i < box.hi[0] - box.lo[0]; ++i) fn(p[base + i], p[base + i + shift]);
    }
}
}  // namespace

namespace {
/// One condition from its JSON object; `key` names it in messages, d is the face's axis.
FaceBc parseFaceBc(const std::string& key, const Json& j, int d, const GlobalGrid& grid,
                   bool heat) {
  const std::string type = j.at("type").get<std::string>();
  FaceBc f;
  if (j.contains("temperature")) {  // optional: absent, no fixed temperature
    f.fixedTemperature = true;
    f.temperature = j.at("temperature").get<double>();
  }
  if (heat && type == "inlet" && !f.fixedTemperature)
    throw ConfigError(key + ".temperature",
                      "fluid.heat = true: an inlet needs the temperature of its inflow (K)");
  if (type == "auto") {
    f.type = grid.periodic[d] ? BcType::Periodic : BcType::Wall;
  } else if (type == "periodic") {
    f.type = BcType::Periodic;
  } else if (type == "inlet") {
    f.type = BcType::Inlet;
    for (int e = 0; e < 3; ++e) f.velocity[e] = j.at("velocity")[e].get<double>();
    f.superficial = j.at("superficial").get<bool>();
  } else if (type == "outlet") {
    f.type = BcType::Outlet;
    f.pressure = j.at("pressure").get<double>();
  } else if (type == "wall") {
    f.type = BcType::Wall;
    for (int e = 0; e < 3; ++e) f.velocity[e] = j.at("velocity")[e].get<double>();
    if (f.velocity[d] != 0.0)
      throw ConfigError(key + ".velocity", std::string("a wall moves only tangentially: its ") +
                                               kAxis[d] + " component must be 0");
  } else if (type == "slip") {
    f.type = BcType::Slip;
  } else {
    throw ConfigError(key + ".type", "unknown boundary type '" + type + "'");
  }
  return f;
}

int faceIndex(const std::string& name) {
  for (int d = 0; d < 3; ++d)
    for (int s = 0; s < 2; ++s)
      if (name == kFace[d][s]) return 2 * d + s;
  return -1;
}
}  // namespace

int BoxBc::code(int axis, int side, int g1, int g2) const {
  const auto& m = map[axis][side];
  if (m.empty()) return 0;
  const int n1 = cells[tangential(axis, 0)], n2 = cells[tangential(axis, 1)];
  g1 = std::clamp(g1, 0, n1 - 1);
  g2 = std::clamp(g2, 0, n2 - 1);
  return m[static_cast<std::size_t>(g1) + static_cast<std::size_t>(n1) * g2];
}

bool BoxBc::anyOnFace(int axis, int side, BcType t) const {
  return (types[axis][side] >> static_cast<unsigned>(t)) & 1u;
}

bool BoxBc::any(BcType t) const {
  for (int d = 0; d < 3; ++d)
    for (int s = 0; s < 2; ++s)
      if (anyOnFace(d, s, t)) return true;
  return false;
}

void checkBoundaryConfig(const Config& cfg, const GlobalGrid& grid) {
  (void)boundaryFromConfig(cfg, grid);
}

BoxBc boundaryFromConfig(const Config& cfg, const GlobalGrid& grid) {
  BoxBc bc;
  bc.cells = grid.cells;
  const bool heat = cfg.boolean("fluid.heat");
  for (int d = 0; d < 3; ++d)
    for (int s = 0; s < 2; ++s) {
      const std::string key = std::string("fluid.boundary.") + kFace[d][s];
      const Json& j = cfg.at(key);
      const std::string type = j.at("type").get<std::string>();
      const FaceBc f = parseFaceBc(key, j, d, grid, heat);
      const bool periodicBc = f.type == BcType::Periodic;
      if (periodicBc != grid.periodic[d])
        throw ConfigError(key, std::string("boundary '") + type +
                                   "' does not match domain.periodic." + kAxis[d] + " = " +
                                   (grid.periodic[d] ? "true" : "false") +
                                   (grid.periodic[d] ? ": use periodic (or auto)"
                                                     : ": periodic needs domain.periodic." +
                                                           std::string(kAxis[d]) + " = true"));
      bc.face[d][s] = f;
    }
  // Patches: rectangles of a face, in metres on the face's two tangential axes (ascending axis
  // order); a face cell belongs to the last patch that contains its face centre.
  const auto finish = [&bc] {
    // Which conditions occur on each face (for anyOnFace, without scanning the maps).
    for (int d = 0; d < 3; ++d)
      for (int s = 0; s < 2; ++s) {
        unsigned t = 1u << static_cast<unsigned>(bc.face[d][s].type);
        const auto& m = bc.map[d][s];
        if (!m.empty()) {
          t = 0;
          std::vector<char> seen(bc.patch.size() + 1, 0);
          for (int c : m) seen[static_cast<std::size_t>(c)] = 1;
          for (std::size_t c = 0; c < seen.size(); ++c)
            if (seen[c])
              t |= 1u << static_cast<unsigned>(bc.byCode(d, s, static_cast<int>(c)).type);
        }
        bc.types[d][s] = t;
      }
    return bc;
  };
  if (!cfg.has("fluid.patches")) return finish();
  const Json& patches = cfg.at("fluid.patches");
  for (std::size_t k = 0; k < patches.size(); ++k) {
    const std::string key = fmt::format("fluid.patches[{}]", k);
    const Json& j = patches[k];
    const std::string faceName = j.at("face").get<std::string>();
    const int fi = faceIndex(faceName);
    if (fi < 0) throw ConfigError(key + ".face", "unknown face '" + faceName + "'");
    const int d = fi / 2, s = fi % 2;
    if (grid.periodic[d])
      throw ConfigError(key + ".face", "face " + faceName + " is periodic (domain.periodic." +
                                           kAxis[d] + "): a patch needs a boundary face");
    const FaceBc f = parseFaceBc(key, j, d, grid, heat);
    const int t[2] = {BoxBc::tangential(d, 0), BoxBc::tangential(d, 1)};
    double lo[2], hi[2];
    for (const char* which : {"min", "max"}) {
      const Json& v = j.at(which);
      if (v.size() != 2)
        throw ConfigError(key + "." + which, std::string("give two coordinates (m), on the ") +
                                                 kAxis[t[0]] + " and " + kAxis[t[1]] +
                                                 " axes of face " + faceName);
    }
    for (int e = 0; e < 2; ++e) {
      lo[e] = j.at("min")[e].get<double>();
      hi[e] = j.at("max")[e].get<double>();
      if (!(lo[e] < hi[e]))
        throw ConfigError(key + ".max", std::string("max must exceed min along ") + kAxis[t[e]]);
    }
    const int n1 = grid.cells[t[0]], n2 = grid.cells[t[1]];
    auto& m = bc.map[d][s];
    if (m.empty()) m.assign(static_cast<std::size_t>(n1) * n2, 0);
    bc.patch.push_back(f);
    const int code = static_cast<int>(bc.patch.size());
    long long covered = 0;
    for (int g2 = 0; g2 < n2; ++g2)
      for (int g1 = 0; g1 < n1; ++g1) {
        const double x1 = grid.origin[t[0]] + (g1 + 0.5) * grid.spacing(t[0]);
        const double x2 = grid.origin[t[1]] + (g2 + 0.5) * grid.spacing(t[1]);
        if (x1 >= lo[0] && x1 <= hi[0] && x2 >= lo[1] && x2 <= hi[1]) {
          m[static_cast<std::size_t>(g1) + static_cast<std::size_t>(n1) * g2] = code;
          ++covered;
        }
      }
    if (covered == 0)
      throw ConfigError(key, "the patch contains no cell face centre of face " + faceName +
                                 " (cell centres at origin + (i + 1/2) h)");
  }
  return finish();
}

namespace {
/// applyVelocityBc on a face with patches: the same rules as on a uniform face, with the
/// condition of each face cell (global indices, clamped into the face for the ghosts beyond
/// the box's edges). A tangential velocity between two face cells of different conditions is
/// Dirichlet if either is (inlet, wall), with the mean of their prescribed values.
void applyPatchedVelocityBc(const Decomposition& dec, const BoxBc& bc, int b, int s, int c,
                            Field3<double>& u, const Field3<double>* eps) {
  const int g = u.layout().ghost;
  const int n = u.layout().n[b];
  const Int3 lo = dec.lo();
  const int t1 = BoxBc::tangential(b, 0), t2 = BoxBc::tangential(b, 1);
  if (c == b) {
    const int face = s == 0 ? 0 : n;
    const int dir = s == 0 ? -1 : 1;
    IndexBox layer = u.allocated();
    layer.lo[b] = face;
    layer.hi[b] = face + 1;
    const IndexBox cells = eps ? eps->allocated() : IndexBox{};
    forEach(layer, [&](int i, int j, int k) {
      const int idx[3] = {i, j, k};
      const FaceBc& f = bc.at(b, s, lo[t1] + idx[t1], lo[t2] + idx[t2]);
      int out[3] = {i, j, k}, in[3] = {i, j, k};
      if (f.type == BcType::Outlet) {
        const double un = u(i, j, k);
        for (int m = 1; m <= g; ++m) {
          out[b] = face + dir * m;
          u(out[0], out[1], out[2]) = un;
        }
        return;
      }
      double un = f.type == BcType::Inlet ? f.velocity[b] : 0.0;
      if (f.type == BcType::Inlet && f.superficial && eps) {
        int ci[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) ci[a] = std::clamp(ci[a], cells.lo[a], cells.hi[a] - 1);
        ci[b] = s == 0 ? 0 : n - 1;
        un = f.velocity[b] / (*eps)(ci[0], ci[1], ci[2]);
      }
      u(i, j, k) = un;
      for (int m = 1; m <= g; ++m) {
        out[b] = face + dir * m;
        in[b] = face - dir * m;
        u(out[0], out[1], out[2]) = 2.0 * un - u(in[0], in[1], in[2]);
      }
    });
    return;
  }
  // Tangential component c: face index along c (between cells f-1 and f), cell index along e.
  const int e = 3 - b - c;
  for (int m = 1; m <= g; ++m) {
    const int ghost = s == 0 ? -m : n - 1 + m;
    const int inner = s == 0 ? m - 1 : n - m;
    IndexBox layer = u.allocated();
    layer.lo[b] = ghost;
    layer.hi[b] = ghost + 1;
    forEach(layer, [&](int i, int j, int k) {
      int idx[3] = {i, j, k};
      int ga[3] = {0, 0, 0}, gb[3] = {0, 0, 0};
      ga[c] = lo[c] + idx[c] - 1;
      gb[c] = lo[c] + idx[c];
      ga[e] = gb[e] = lo[e] + idx[e];
      const int ca = bc.code(b, s, ga[t1], ga[t2]), cb = bc.code(b, s, gb[t1], gb[t2]);
      const FaceBc& fa = bc.byCode(b, s, ca);
      const FaceBc& fb = bc.byCode(b, s, cb);
      const auto dirichlet = [](const FaceBc& f) {
        return f.type == BcType::Inlet || f.type == BcType::Wall;
      };
      bool dir = false;
      double ut = 0;
      if (ca == cb) {
        dir = dirichlet(fa);
        ut = dir ? fa.velocity[c] : 0.0;
      } else if (dirichlet(fa) && dirichlet(fb)) {
        dir = true;
        ut = 0.5 * (fa.velocity[c] + fb.velocity[c]);
      } else if (dirichlet(fa) || dirichlet(fb)) {
        dir = true;
        ut = dirichlet(fa) ? fa.velocity[c] : fb.velocity[c];
      }
      const double src = [&] {
        idx[b] = inner;
        return u(idx[0], idx[1], idx[2]);
      }();
      u(i, j, k) = dir ? 2.0 * ut - src : src;
    });
  }
}
}  // namespace

void applyVelocityBc(const Decomposition& dec, const BoxBc& bc, int c, Field3<double>& u,
                     const Field3<double>* eps) {
  const int g = u.layout().ghost;
  for (int b = 0; b < 3; ++b) {
    const int n = u.layout().n[b];
    for (int s = 0; s < 2; ++s) {
      if (s == 0 ? !dec.atLowBoundary(b) : !dec.atHighBoundary(b)) continue;
      if (!bc.uniform(b, s)) {
        applyPatchedVelocityBc(dec, bc, b, s, c, u, eps);
        continue;
      }
      const FaceBc& f = bc.face[b][s];
      if (c == b) {
        // Normal component: boundary face 0 (low) or n (high), ghosts beyond it.
        const int face = s == 0 ? 0 : n;
        const int dir = s == 0 ? -1 : 1;
        if (f.type == BcType::Inlet && f.superficial && eps) {
          // The inlet velocity is superficial (a volume flux per area): the face carries
          // u = U / eps of the adjacent cell, so that eps u = U whatever the bed touching it.
          IndexBox layer = u.allocated();
          layer.lo[b] = face;
          layer.hi[b] = face + 1;
          const IndexBox cells = eps->allocated();
          const double U = f.velocity[b];
          forEach(layer, [&](int i, int j, int k) {
            int ci[3] = {i, j, k};
            for (int a = 0; a < 3; ++a) ci[a] = std::clamp(ci[a], cells.lo[a], cells.hi[a] - 1);
            ci[b] = s == 0 ? 0 : n - 1;
            const double un = U / (*eps)(ci[0], ci[1], ci[2]);
            u(i, j, k) = un;
            for (int m = 1; m <= g; ++m) {
              int out[3] = {i, j, k}, in[3] = {i, j, k};
              out[b] = face + dir * m;
              in[b] = face - dir * m;
              u(out[0], out[1], out[2]) = 2.0 * un - u(in[0], in[1], in[2]);
            }
          });
        } else if (f.type != BcType::Outlet) {
          const double un = f.type == BcType::Inlet ? f.velocity[b] : 0.0;
          forLayer(u, b, face, face, [&](double& dst, double&) { dst = un; });
          for (int m = 1; m <= g; ++m) {
            // u(face + dir m) = 2 u(face) - u(face - dir m)
            forLayer(u, b, face + dir * m, face - dir * m,
                     [&](double& dst, double& src) { dst = 2.0 * un - src; });
          }
        } else {
          for (int m = 1; m <= g; ++m)
            forLayer(u, b, face + dir * m, face, [&](double& dst, double& src) { dst = src; });
        }
      } else {
        // Tangential component: cell-centred along b; ghost layer m mirrors inner layer m-1.
        const bool dirichlet = f.type == BcType::Inlet || f.type == BcType::Wall;
        const double ut = dirichlet ? f.velocity[c] : 0.0;
        for (int m = 1; m <= g; ++m) {
          const int ghost = s == 0 ? -m : n - 1 + m;
          const int inner = s == 0 ? m - 1 : n - m;
          if (dirichlet)
            forLayer(u, b, ghost, inner, [&](double& dst, double& src) { dst = 2.0 * ut - src; });
          else
            forLayer(u, b, ghost, inner, [&](double& dst, double& src) { dst = src; });
        }
      }
    }
  }
}

void applyScalarBc(const Decomposition& dec, Field3<double>& f) {
  const int g = f.layout().ghost;
  for (int b = 0; b < 3; ++b) {
    const int n = f.layout().n[b];
    for (int s = 0; s < 2; ++s) {
      if (s == 0 ? !dec.atLowBoundary(b) : !dec.atHighBoundary(b)) continue;
      for (int m = 1; m <= g; ++m) {
        const int ghost = s == 0 ? -m : n - 1 + m;
        const int inner = s == 0 ? std::min(m - 1, n - 1) : std::max(n - m, 0);
        forLayer(f, b, ghost, inner, [&](double& dst, double& src) { dst = src; });
      }
    }
  }
}

void predictBoxFaces(const Decomposition& dec, const BoxBc& bc, int c, Field3<double>& u,
                     Field3<double>& uPrev) {
  double* up = u.data().data();
  double* pp = uPrev.data().data();
  const std::ptrdiff_t stride = u.stride(c);
  for (int s = 0; s < 2; ++s) {
    const std::ptrdiff_t sh = s == 0 ? stride : -stride;
    forBoxFace(dec, bc, c, s, [&](int i, int j, int k, const FaceBc& fb) {
      const std::ptrdiff_t q = u.index(i, j, k);
      pp[q] = up[q];
      if (fb.type == BcType::Outlet) up[q] = up[q + sh];
    });
  }
}

void projectOutletFaces(const Decomposition& dec, const BoxBc& bc, int c, Field3<double>& u,
                        const Field3<double>& eps, const Field3<double>& K, const Field3<double>& p,
                        double dt, double ih) {
  double* up = u.data().data();
  const double* en = eps.data().data();
  const double* kk = K.data().data();
  const double* pp = p.data().data();
  const std::ptrdiff_t cs = eps.stride(c);
  for (int s = 0; s < 2; ++s) {
    if (!bc.anyOnFace(c, s, BcType::Outlet)) continue;
    forBoxFace(dec, bc, c, s, [&](int i, int j, int k, const FaceBc& fb) {
      if (fb.type != BcType::Outlet) return;
      const std::ptrdiff_t q = u.index(i, j, k);
      const std::ptrdiff_t cc = s == 0 ? eps.index(i, j, k) : eps.index(i, j, k) - cs;
      const double ef = en[cc], kf = kk[cc];
      up[q] -= ef / (ef + kf * dt) * outletDifference(s, pp[cc], fb.pressure) * 2.0 * ih;
    });
  }
}

}  // namespace coloc::fv
