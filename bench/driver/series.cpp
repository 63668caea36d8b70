// The per-step time series, OUT/series.csv (series.hpp).
#include "series.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <span>

#include "coloc/core/error.hpp"
#include "coloc/core/fault.hpp"
#include "coloc/core/files.hpp"

namespace coloc {

Series::Series(const Comm& comm, const std::string& path, coupling::Simulation& sim,
               const Config& cfg)
    : comm_(comm), cfg_(cfg) {
  auto* dem = sim.particles();
  const long long total = dem ? dem->globalCount() : 0;
  const Json& ids = cfg.at("output.series_particle_ids");
  if (!ids.empty()) {
    for (const auto& v : ids) {
      const double x = v.get<double>();
      if (x != std::floor(x) || x < 0 || x >= static_cast<double>(total)) {
        throw ConfigError(
            "output.series_particle_ids",
            fmt::format("particle id {:.17g} is not one of the ids 0..{}", x, total - 1));
      }
      ids_.push_back(static_cast<long long>(x));
    }
  } else {
    for (long long i = 0; i < std::min<long long>(total, cfg.integer("output.series_particles"));
         ++i)
      ids_.push_back(i);
  }
  if (!ids_.empty())
    column_.assign(static_cast<std::size_t>(*std::max_element(ids_.begin(), ids_.end())) + 1, -1);
  for (std::size_t c = 0; c < ids_.size(); ++c)
    column_[static_cast<std::size_t>(ids_[c])] = static_cast<long long>(c);
  row_.resize(9 * ids_.size());
  diagEvery_ = cfg.integer("output.diagnostics_interval");
  if (diagEvery_ == 0) diagEvery_ = cfg.integer("output.interval_steps");
  if (!comm_.isRoot()) return;
  path_ = path;
  std::string header = "step,time,solid_volume,fluid_accel_l1";
  for (long long id : ids_)
    for (const char* q : {"x", "y", "z", "vx", "vy", "vz", "fx", "fy", "fz"})
      header += ",p" + std::to_string(id) + "_" + q;
  for (const auto& c : bedDiagnosticsColumns()) header += "," + c;
  header += "\n";
  line_.reserve(32 * (4 + 9 * ids_.size() + bedDiagnosticsColumns().size()));
  // A regular file only, made afresh as series.csv.tmp (never through a link) and renamed over
  // a regular file or nothing (coloc/core/files.hpp); the rows are appended to it after that.
  if (const std::string why = writeTargetProblem(path); !why.empty()) throw IoError(why);
  const std::string tmp = path + ".tmp";
  fd_ = createFresh(tmp);
  if (::fcntl(fd_, F_SETFL, O_APPEND) != 0 || !append(header)) {
    const std::string why = std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
    ::unlink(tmp.c_str());
    throw IoError("cannot write '" + path + "': " + why);
  }
  if (const std::string err = publishFile(tmp, path); !err.empty()) {
    ::close(fd_);
    fd_ = -1;
    throw IoError(err);
  }
}

Series::~Series() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<BedDiagnostics> Series::record(coupling::Simulation& sim) {
  std::vector<double>& row = row_;
  std::fill(row.begin(), row.end(), 0.0);
  if (auto* dem = sim.particles(); dem && !column_.empty()) {
    const auto& p = dem->particles();
    const auto n = static_cast<std::int64_t>(column_.size());
    for (std::size_t i = 0; i < p.nOwned; ++i) {
      const std::int64_t id = p.id[i];
      if (id < 0 || id >= n || column_[static_cast<std::size_t>(id)] < 0) continue;
      double* r = row.data() + 9 * column_[static_cast<std::size_t>(id)];
      for (int d = 0; d < 3; ++d) {
        r[d] = p.x[d][i];
        r[3 + d] = p.v[d][i];
        r[6 + d] = p.fExt[d][i];
      }
    }
  }
  comm_.sumInPlace(std::span<double>(row));
  std::optional<BedDiagnostics> diag;
  if ((diagEvery_ > 0 && sim.steps() % diagEvery_ == 0) || sim.finished())
    diag = bedDiagnostics(sim, cfg_);
  if (!comm_.isRoot() || fd_ < 0 || !error_.empty()) return diag;
  try {
    fault::point("series", sim.steps());
  } catch (const std::exception& e) {
    error_ = e.what();
    return diag;
  }
  char buf[64];
  line_ = std::to_string(sim.steps());
  for (double v : {sim.time(), sim.depositedSolidVolume(), sim.fluidAccelerationL1()}) {
    std::snprintf(buf, sizeof buf, ",%.17g", v);
    line_ += buf;
  }
  for (double v : row) {
    std::snprintf(buf, sizeof buf, ",%.17g", v);
    line_ += buf;
  }
  if (diag) {
    for (double v : bedDiagnosticsRow(*diag)) {
      std::snprintf(buf, sizeof buf, ",%.17g", v);
      line_ += buf;
    }
  } else {
    line_ += std::string(bedDiagnosticsColumns().size(), ',');
  }
  line_ += "\n";
  if (!append(line_))
    error_ = "cannot append to '" + path_ + "': " + std::strerror(errno) +
             " (the rows before this step are kept)";
  return diag;
}

void Series::sync() {
  if (fd_ >= 0) ::fsync(fd_);
}

bool Series::append(const std::string& text) {
  const off_t before = ::lseek(fd_, 0, SEEK_END);
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = n == 0 ? ENOSPC : errno;
      if (before >= 0 && ::ftruncate(fd_, before) != 0) {
      }
      errno = e;
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace coloc
