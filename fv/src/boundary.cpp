#include "boundary.hpp"

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
  const std::ptrdiff_t stride = b == 0 ? 1 : b == 1 ? f.strideY() : f.strideZ();
  const std::ptrdiff_t shift = static_cast<std::ptrdiff_t>(srcLayer - layer) * stride;
  double* p = f.data().data();
  for (int k = box.lo[2]; k < box.hi[2]; ++k)
    for (int j = box.lo[1]; j < box.hi[1]; ++j) {
      const std::ptrdiff_t base = f.index(box.lo[0], j, k);
      for (int i = 0; i < box.hi[0] - box.lo[0]; ++i) fn(p[base + i], p[base + i + shift]);
    }
}
}  // namespace

void checkBoundaryConfig(const Config& cfg, const GlobalGrid& grid) {
  (void)boundaryFromConfig(cfg, grid);
}

BoxBc boundaryFromConfig(const Config& cfg, const GlobalGrid& grid) {
  BoxBc bc;
  for (int d = 0; d < 3; ++d)
    for (int s = 0; s < 2; ++s) {
      const std::string key = std::string("fluid.boundary.") + kFace[d][s];
      const Json& j = cfg.at(key);
      const std::string type = j.at("type").get<std::string>();
      FaceBc f;
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
      const bool periodicBc = f.type == BcType::Periodic;
      if (periodicBc != grid.periodic[d])
        throw ConfigError(key, std::string("boundary '") + type +
                                   "' does not match domain.periodic." + kAxis[d] + " = " +
                                   (grid.periodic[d] ? "true" : "false") +
                                   (grid.periodic[d] ? ": use periodic (or auto)"
                                                     : ": periodic needs domain.periodic." +
                                                           std::string(kAxis[d]) + " = true"));
      bc[d][s] = f;
    }
  return bc;
}

void applyVelocityBc(const Decomposition& dec, const BoxBc& bc, int c, Field3<double>& u,
                     const Field3<double>* eps) {
  const int g = u.layout().ghost;
  for (int b = 0; b < 3; ++b) {
    const int n = u.layout().n[b];
    for (int s = 0; s < 2; ++s) {
      if (s == 0 ? !dec.atLowBoundary(b) : !dec.atHighBoundary(b)) continue;
      const FaceBc& f = bc[b][s];
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

}  // namespace coloc::fv
