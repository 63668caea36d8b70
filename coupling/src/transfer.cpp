#include "coloc/coupling/transfer.hpp"

#include <fmt/format.h>

#include <cmath>
#include <string>
#include <vector>

#include "coloc/partition/comm_plan.hpp"

namespace coloc::coupling {

namespace {

class Colocated final : public ParticleTransfer {
 public:
  Colocated(dem::DemSolver& dem, bool heat) : dem_(dem), heat_(heat) {}
  ParticleView gather(Timers&) override {
    const auto& p = dem_.particles();
    ParticleView v;
    v.n = p.nOwned;
    for (int d = 0; d < 3; ++d) {
      v.x[d] = p.x[d].data();
      v.v[d] = p.v[d].data();
      v.force[d] = p.f[d].data();
      v.held[d] = p.fExt[d].data();
    }
    v.radius = p.radius.data();
    v.mass = p.mass.data();
    v.id = p.id.data();
    if (heat_) {
      v.temperature = p.field("temperature").data();
      v.material = p.material.data();
    }
    n_ = v.n;
    return v;
  }
  std::array<double*, 3> forceTarget() override {
    auto& p = dem_.particles();
    return {p.fExt[0].data(), p.fExt[1].data(), p.fExt[2].data()};
  }
  double* heatTarget() override {
    return heat_ ? dem_.particles().field("heat_ext").data() : nullptr;
  }
  void handBack(Timers& timers) override {
    // The forces (and heat rates) are already in the DEM's own arrays: what crossed from one
    // physics to the other is those bytes, in memory, with no copy and no message.
    const std::size_t perParticle = kForceRowDoubles + (heat_ ? kHeatRowDoubles : 0);
    timers.book(Exchange::InterPhysicsLocal,
                static_cast<long long>(perParticle * n_ * sizeof(double)), 0);
  }

 private:
  dem::DemSolver& dem_;
  bool heat_ = false;
  std::size_t n_ = 0;
};

class Proxy final : public ParticleTransfer {
 public:
  // x3 v3 nonDrag3 radius mass id [temperature material]; back: force3 [heat rate]
  Proxy(const Decomposition& fluid, dem::DemSolver& dem, bool heat)
      : dec_(fluid),
        dem_(dem),
        heat_(heat),
        row_(kProxyRowDoubles + (heat ? kProxyHeatDoubles : 0)),
        back_(kForceRowDoubles + (heat ? kHeatRowDoubles : 0)) {}

  ParticleView gather(Timers& timers) override {
    const auto& p = dem_.particles();
    const std::size_t n = p.nOwned;
    // Every particle's coupling data goes to the rank whose fluid block holds it (on one rank
    // the rows stay in memory: an exchange inside the rank).
    ScopedPhase t(timers, dec_.comm().size() > 1 ? Phase::ExchangeRemote : Phase::ExchangeLocal);
    const double t0 = MPI_Wtime();
    const auto& g = dec_.grid();
    grow(dest_, n);
    std::string err;
    for (std::size_t i = 0; i < n; ++i) {
      const int r = dec_.ownerOfPoint({p.x[0][i], p.x[1][i], p.x[2][i]});
      if (r < 0 && err.empty()) err = fmt::format("particle {} is outside the box", p.id[i]);
      dest_[i] = std::max(r, 0);
    }
    dec_.comm().raiseIfAny(err);
    if (!built_) {
      plan_ = CommPlan::fromDestinations(dec_.comm(), std::span<const int>(dest_.data(), n));
      built_ = true;
    } else {
      plan_.rebuild(std::span<const int>(dest_.data(), n));
    }
    // Rows packed straight into the plan's send buffer, in destination order.
    const std::span<double> rows = plan_.packBuffer(row_);
    const std::span<const int> order = plan_.exportIndex();
    const double* T = heat_ ? p.field("temperature").data() : nullptr;
    for (std::size_t k = 0; k < n; ++k) {
      const auto i = static_cast<std::size_t>(order[k]);
      double* row = rows.data() + k * row_;
      for (int d = 0; d < 3; ++d) {
        double xd = p.x[d][i];
        if (g.periodic[d]) {  // wrap into the box: the fluid owner's block frame
          xd = g.origin[d] + std::fmod(xd - g.origin[d], g.length[d]);
          if (xd < g.origin[d]) xd += g.length[d];
        }
        row[d] = xd;
        row[3 + d] = p.v[d][i];
        row[6 + d] = p.f[d][i] - p.fExt[d][i];
      }
      row[9] = p.radius[i];
      row[10] = p.mass[i];
      row[11] = static_cast<double>(p.id[i]);
      if (heat_) {
        row[12] = T[i];
        row[13] = static_cast<double>(p.material[i]);
      }
    }
    const std::size_t m = plan_.importCount();
    grow(in_, m * row_);
    const PlanTraffic tr = plan_.forwardPacked(row_, std::span<double>(in_.data(), m * row_));
    if (radius_.size() < m) {
      const std::size_t cap = m + m / 4;
      for (int d = 0; d < 3; ++d)
        for (auto* a : {&x_, &v_, &nonDrag_, &force_}) (*a)[d].resize(cap);
      radius_.resize(cap);
      mass_.resize(cap);
      id_.resize(cap);
      if (heat_) {
        temperature_.resize(cap);
        heatRate_.resize(cap);
        material_.resize(cap);
      }
    }
    for (std::size_t k = 0; k < m; ++k) {
      const double* row = in_.data() + k * row_;
      for (int d = 0; d < 3; ++d) {
        x_[d][k] = row[d];
        v_[d][k] = row[3 + d];
        nonDrag_[d][k] = row[6 + d];
      }
      radius_[k] = row[9];
      mass_[k] = row[10];
      id_[k] = static_cast<std::int64_t>(row[11]);
      if (heat_) {
        temperature_[k] = row[12];
        material_[k] = static_cast<int>(row[13]);
      }
    }
    ParticleView view;
    view.n = m;
    for (int d = 0; d < 3; ++d) {
      view.x[d] = x_[d].data();
      view.v[d] = v_[d].data();
      view.force[d] = nonDrag_[d].data();
      view.held[d] = nullptr;
    }
    view.radius = radius_.data();
    view.mass = mass_.data();
    view.id = id_.data();
    if (heat_) {
      view.temperature = temperature_.data();
      view.material = material_.data();
    }
    book(timers, tr, MPI_Wtime() - t0);
    return view;
  }

  std::array<double*, 3> forceTarget() override {
    return {force_[0].data(), force_[1].data(), force_[2].data()};
  }

  double* heatTarget() override { return heat_ ? heatRate_.data() : nullptr; }

  void handBack(Timers& timers) override {
    // The forces (and heat rates) travel back to the DEM ranks through the same plan, reversed.
    ScopedPhase t(timers, dec_.comm().size() > 1 ? Phase::ExchangeRemote : Phase::ExchangeLocal);
    const double t0 = MPI_Wtime();
    auto& p = dem_.particles();
    const std::size_t m = plan_.importCount(), n = plan_.exportCount(), w = back_;
    grow(in_, w * m);
    for (std::size_t k = 0; k < m; ++k) {
      for (int d = 0; d < 3; ++d) in_[w * k + static_cast<std::size_t>(d)] = force_[d][k];
      if (heat_) in_[w * k + 3] = heatRate_[k];
    }
    grow(rows_, w * n);
    const PlanTraffic tr = plan_.reverseInExportOrder(
        std::span<const double>(in_.data(), w * m), back_, std::span<double>(rows_.data(), w * n));
    const std::span<const int> order = plan_.exportIndex();
    double* qExt = heat_ ? p.field("heat_ext").data() : nullptr;
    for (std::size_t k = 0; k < n; ++k) {
      const auto i = static_cast<std::size_t>(order[k]);
      for (int d = 0; d < 3; ++d) p.fExt[d][i] = rows_[w * k + static_cast<std::size_t>(d)];
      if (heat_) qExt[i] = rows_[w * k + 3];
    }
    book(timers, tr, MPI_Wtime() - t0);
  }

 private:
  template <class T>
  static void grow(std::vector<T>& v, std::size_t n) {
    if (v.size() < n) v.resize(n + n / 4);
  }
  /// Rows to other ranks are messages; the rows a rank keeps for itself move in memory. The time
  /// goes with the bytes: across ranks when any row left the rank.
  static void book(Timers& timers, const PlanTraffic& tr, double seconds) {
    timers.book(Exchange::InterPhysicsRemote, tr.remoteBytes, tr.messages,
                tr.messages > 0 ? seconds : 0.0, Traffic::Proxy);
    timers.book(Exchange::InterPhysicsLocal, tr.localBytes, 0, tr.messages > 0 ? 0.0 : seconds,
                Traffic::ForceHandover);
  }

  const Decomposition& dec_;
  dem::DemSolver& dem_;
  bool heat_ = false;
  int row_ = kProxyRowDoubles, back_ = kForceRowDoubles;
  CommPlan plan_;
  bool built_ = false;
  std::vector<int> dest_;
  std::vector<double> rows_, in_;
  std::array<std::vector<double>, 3> x_, v_, nonDrag_, force_;
  std::vector<double> radius_, mass_, temperature_, heatRate_;
  std::vector<std::int64_t> id_;
  std::vector<int> material_;
};

}  // namespace

std::unique_ptr<ParticleTransfer> colocatedTransfer(dem::DemSolver& dem, bool heat) {
  return std::make_unique<Colocated>(dem, heat);
}

std::unique_ptr<ParticleTransfer> proxyTransfer(const Decomposition& fluid, dem::DemSolver& dem,
                                                bool heat) {
  return std::make_unique<Proxy>(fluid, dem, heat);
}

}  // namespace coloc::coupling
