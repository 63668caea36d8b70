// coloc/io/output.hpp — periodic output of a run: fluid fields and particles to parallel
// HDF5, one file per output time, and one XDMF index per series for ParaView (docs/output.md).
//
//   DIR/fields_NNNNNN.h5      one dataset per field: scalar [nz][ny][nx], vector [nz][ny][nx][3]
//   DIR/particles_NNNNNN.h5   id, x, v, omega, radius, rank  ([N] or [N][3]), vertex [N]
//   DIR/fields.xmf, DIR/particles.xmf   temporal collections of every output so far
//
// NNNNNN is the step (zero-padded to 6 digits, more if needed). Each .h5 is written through
// NAME.tmp and renamed; the .xmf files are rewritten by rank 0 (temp file + rename) after each
// output, so a viewer or a killed run never sees a half-written file.
//
// Usage (the run loop):
//   Schema s; declareOutputConfig(s); ...
//   OutputWriter out(dec, outputOptionsFromConfig(cfg, outDir));
//   if (out.due(step)) {
//     out.writeFields(step, t, {OutputField::scalar("p", f.p), OutputField::vector("u", uc)});
//     out.writeParticles(step, t, ids, firstRows(p.x, n), firstRows(p.v, n), ...);
//   }
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "coloc/core/config.hpp"
#include "coloc/io/checkpoint_file.hpp"
#include "coloc/io/h5io.hpp"
#include "coloc/io/xdmf.hpp"

namespace coloc {

struct OutputOptions {
  long long intervalSteps = 0;  // 0: no periodic output
  bool fields = true;
  bool particles = true;
  std::string dir = ".";
};

/// output.{interval_steps,fields,particles,dir,series_*,diagnostics_interval,snapshot} and the
/// checkpoint keys output.checkpoint_{interval,file,on_failure} (coloc/io/checkpoint_file.hpp).
void declareOutputConfig(Schema& s);
/// The options of a case; output.dir "" means `runOutDir` (the run's --out folder).
OutputOptions outputOptionsFromConfig(const Config& cfg, const std::string& runOutDir);

/// A cell field to write: a scalar (c[0]) or a 3-vector (c[0..2]). `units` (e.g. "m/s", "1" for
/// a dimensionless field) goes into the dataset's `units` attribute; empty: no attribute.
struct OutputField {
  std::string name;
  std::array<const CellField*, 3> c{};
  std::string units;
  bool isVector() const { return c[1] != nullptr; }
  static OutputField scalar(std::string name, const CellField& f, std::string units = {}) {
    return {std::move(name), {&f, nullptr, nullptr}, std::move(units)};
  }
  static OutputField vector(std::string name, const CellField& x, const CellField& y,
                            const CellField& z, std::string units = {}) {
    return {std::move(name), {&x, &y, &z}, std::move(units)};
  }
  static OutputField vector(std::string name, const std::array<CellField, 3>& v,
                            std::string units = {}) {
    return vector(std::move(name), v[0], v[1], v[2], std::move(units));
  }
};

/// The optional columns of a particle file: written when `write` is true, which must be the same
/// on every rank (the datasets are created collectively, and a rank may hold no particle).
struct ParticleExtraColumns {
  bool write = false;
  std::span<const int> material;  ///< material index of each particle (`particles.materials`)
  Vec3Span fluidForce;            ///< the fluid's force on each particle (N), as the DEM used it
  /// With `temperature` true (the same on every rank): /temperature, the particle temperature (K)
  /// of particles.heat.
  bool temperature = false;
  std::span<const double> temperatureK{};
};

/// Writes the output series of a run. Collective calls (every rank of the decomposition); the
/// decomposition must outlive the writer.
class OutputWriter {
 public:
  /// Creates opt.dir (all parents) when any output is enabled; coloc::Error on every rank if it
  /// cannot.
  OutputWriter(const Decomposition& dec, OutputOptions opt);

  const OutputOptions& options() const { return opt_; }
  /// Writes from now on for the blocks of `dec` (after a re-balance); the series go on.
  void rebind(const Decomposition& dec) { dec_ = &dec; }
  /// True when `step` is an output step (intervalSteps > 0 and step % intervalSteps == 0).
  bool due(long long step) const;

  /// Writes DIR/fields_NNNNNN.h5 and rewrites DIR/fields.xmf; returns the .h5 path. Does
  /// nothing (returns "") when options().fields is false. Names: non-empty, no '/', unique, not
  /// "rank": the writer adds /rank, the rank that owns each cell (ParaView colours the partition
  /// by it, as by vtkProcessId).
  std::string writeFields(long long step, double time, const std::vector<OutputField>& fields);

  /// Writes this rank's particles (all spans of one length, e.g. the owned particles) to
  /// DIR/particles_NNNNNN.h5 with the owning rank and the vertex list (/vertex: the row index,
  /// the XDMF topology's connectivity), and rewrites DIR/particles.xmf; returns the
  /// .h5 path. Does nothing (returns "") when options().particles is false.
  /// With `extra.write` (the same on every rank), also /material and /fluid_force; with
  /// `extra.temperature` also /temperature.
  std::string writeParticles(long long step, double time, std::span<const std::int64_t> id,
                             Vec3Span x, Vec3Span v, Vec3Span omega, std::span<const double> radius,
                             const ParticleExtraColumns& extra = {});

  const XdmfSeries& fieldSeries() const { return fieldSeries_; }
  const XdmfSeries& particleSeries() const { return particleSeries_; }
  /// "fields_000042.h5" / "particles_000042.h5".
  static std::string fileName(const std::string& series, long long step);

 private:
  void ensureDir();
  const Decomposition* dec_;
  OutputOptions opt_;
  bool dirReady_ = false;
  XdmfSeries fieldSeries_, particleSeries_;
  CellField rank_;  // this rank's number on its cells (rebuilt when its block changes)
};

}  // namespace coloc
