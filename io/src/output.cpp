#include "coloc/io/output.hpp"

#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <set>
#include <utility>

#include "coloc/core/error.hpp"
#include "coloc/core/fault.hpp"
#include "coloc/core/report.hpp"

namespace coloc {

void declareOutputConfig(Schema& s) {
  s.integer("output.interval_steps", 0,
            "write fields and particles every this many steps (0: no periodic output)",
            Range::nonNegative());
  s.boolean("output.fields", true, "write the fluid fields (DIR/fields_NNNNNN.h5, fields.xmf)");
  s.boolean("output.particles", true,
            "write the particles (DIR/particles_NNNNNN.h5, particles.xmf)");
  s.string("output.dir", "", "folder of the HDF5/XDMF output (empty: the run's --out folder)");
  s.integer("output.series_particles", 4,
            "series.csv follows the particles with ids 0..N-1 (position, velocity, coupling "
            "force each step)",
            Range::nonNegative());
  s.numberList("output.series_particle_ids", std::vector<double>{},
               "series.csv follows these particle ids instead (e.g. [0, 17, 4711]); empty: "
               "output.series_particles");
  s.integer("output.diagnostics_interval", 0,
            "bed diagnostics (bed height, particle speeds, contacts, pressure drops, solid "
            "fraction) in series.csv every this many steps and at the last step; 0: on the "
            "output steps (output.interval_steps), or only the last step without periodic "
            "output; report.json's 'bed' holds the last",
            Range::nonNegative());
  s.boolean("output.snapshot", true,
            "at the end of a run that writes fields, rank 0 draws the last output to "
            "snapshot.png in the run's --out folder (bench/scripts/snapshot.py, /usr/bin/python3 "
            "with h5py and matplotlib); a failure to draw is a warning, not an error");
  s.integer("output.checkpoint_interval", 0,
            "write a restart checkpoint every this many steps, and at the end of the run "
            "(0: none); coloc run CASE --restart FILE continues from one (docs/output.md)",
            Range::nonNegative());
  s.string("output.checkpoint_file", "checkpoint.h5",
           "checkpoint file, relative to output.dir; each checkpoint replaces it atomically "
           "(written as FILE.tmp, renamed when complete); {step} in the name is replaced by the "
           "zero-padded step to keep every checkpoint (e.g. ck_{step}.h5); it stays inside "
           "output.dir (no absolute path, no '..') and is none of the run's own files "
           "(report.json, series.csv, fields_*.h5, ...)");
  s.boolean("output.checkpoint_on_failure", true,
            "when the run fails (NaN, CFL, a particle leaving the box, ...), write the state at "
            "the failure to FILE with .failed before .h5 (status attribute 'failed: ...'); the "
            "last good checkpoint is kept");
}

OutputOptions outputOptionsFromConfig(const Config& cfg, const std::string& runOutDir) {
  OutputOptions o;
  o.intervalSteps = cfg.integer("output.interval_steps");
  o.fields = cfg.boolean("output.fields");
  o.particles = cfg.boolean("output.particles");
  o.dir = cfg.string("output.dir");
  if (o.dir.empty()) o.dir = runOutDir.empty() ? "." : runOutDir;
  return o;
}

OutputWriter::OutputWriter(const Decomposition& dec, OutputOptions opt)
    : dec_(&dec),
      opt_(std::move(opt)),
      fieldSeries_(XdmfSeries::cells("fields", dec.grid())),
      particleSeries_(XdmfSeries::particles("particles")) {
  if (opt_.dir.empty()) opt_.dir.push_back('.');
  if (opt_.intervalSteps > 0 && (opt_.fields || opt_.particles)) ensureDir();
}

bool OutputWriter::due(long long step) const {
  return opt_.intervalSteps > 0 && step % opt_.intervalSteps == 0;
}

std::string OutputWriter::fileName(const std::string& series, long long step) {
  char b[64];
  std::snprintf(b, sizeof b, "_%06lld.h5", step);
  return series + b;
}

void OutputWriter::ensureDir() {
  if (dirReady_) return;
  std::string err;
  if (dec_->comm().isRoot()) {
    try {
      makeDirectories(opt_.dir);
    } catch (const std::exception& e) {
      err = std::string("output directory: ") + e.what();
    }
  }
  if (const std::string msg = dec_->comm().firstError(err, 4); !msg.empty()) throw IoError(msg);
  dirReady_ = true;
}

std::string OutputWriter::writeFields(long long step, double time,
                                      const std::vector<OutputField>& fields) {
  if (!opt_.fields) return {};
  std::set<std::string> names;
  for (const auto& f : fields) {
    if (f.name.empty() || f.name.find('/') != std::string::npos || f.name == "rank" ||
        !names.insert(f.name).second)
      throw Error("output field name '" + f.name +
                  "': must be non-empty, unique, without '/', not 'rank'");
    if (!f.c[0] || (f.isVector() && !f.c[2]))
      throw Error("output field '" + f.name + "': missing component");
  }
  ensureDir();
  const Decomposition& dec = *dec_;
  if (rank_.layout().n != dec.cells() || rank_.data().empty())
    rank_ = CellField(FieldLayout{dec.cells(), 0, {0, 0, 0}}, double(dec.comm().rank()));
  std::vector<OutputField> all = fields;
  all.push_back(OutputField::scalar("rank", rank_, "1"));
  const std::string name = fileName("fields", step);
  const std::string path = (std::filesystem::path(opt_.dir) / name).string();
  XdmfStep entry;
  entry.time = time;
  entry.step = step;
  entry.file = name;
  {
    H5File file = H5File::create(dec.comm(), path);
    file.setAttribute("/", "time", time);
    file.setAttribute("/", "time_units", "s");
    file.setAttribute("/", "step", step);
    const auto& g = dec.grid();
    const double cells[3] = {double(g.cells[0]), double(g.cells[1]), double(g.cells[2])};
    const double spacing[3] = {g.spacing(0), g.spacing(1), g.spacing(2)};
    file.setAttribute("/", "origin", std::span<const double>(g.origin));
    file.setAttribute("/", "spacing", std::span<const double>(spacing));
    file.setAttribute("/", "cells", std::span<const double>(cells));
    file.setAttribute("/", "length_units", "m");
    for (const auto& f : all) {
      const std::string ds = "/" + f.name;
      if (f.isVector())
        writeCellVector(file, ds, dec, *f.c[0], *f.c[1], *f.c[2]);
      else
        writeCellField(file, ds, dec, *f.c[0]);
      if (!f.units.empty()) file.setAttribute(ds, "units", f.units);
      entry.attributes.push_back({f.name, f.isVector(), ds});
      if (entry.attributes.size() == 1) fault::point("output", step);  // inside an open file
    }
    file.close();
  }
  fieldSeries_.add(std::move(entry));
  fieldSeries_.write(dec.comm(), (std::filesystem::path(opt_.dir) / "fields.xmf").string());
  return path;
}

std::string OutputWriter::writeParticles(long long step, double time,
                                         std::span<const std::int64_t> id, Vec3Span x, Vec3Span v,
                                         Vec3Span omega, std::span<const double> radius,
                                         const ParticleExtraColumns& extra) {
  if (!opt_.particles) return {};
  const Decomposition& dec = *dec_;
  const std::size_t n = id.size();
  std::string err;
  for (const Vec3Span* a : {&x, &v, &omega})
    for (const auto& c : *a)
      if (c.size() != n) err = "particle output: arrays of different lengths";
  if (radius.size() != n) err = "particle output: arrays of different lengths";
  if (extra.write) {
    if (extra.material.size() != n) err = "particle output: arrays of different lengths";
    for (const auto& c : extra.fluidForce)
      if (c.size() != n) err = "particle output: arrays of different lengths";
  }
  if (extra.temperature && extra.temperatureK.size() != n)
    err = "particle output: arrays of different lengths";
  dec.comm().raiseIfAny(err);
  ensureDir();
  const std::string name = fileName("particles", step);
  const std::string path = (std::filesystem::path(opt_.dir) / name).string();
  XdmfStep entry;
  entry.time = time;
  entry.step = step;
  entry.file = name;
  entry.geometry = "/x";
  entry.connectivity = "/vertex";
  {
    H5File file = H5File::create(dec.comm(), path);
    const long long total = dec.comm().sum(static_cast<long long>(n));
    entry.count = total;
    file.setAttribute("/", "time", time);
    file.setAttribute("/", "step", step);
    file.setAttribute("/", "count", total);
    writeParticleArray(file, "/id", id);
    writeParticleVec3(file, "/x", x);
    writeParticleVec3(file, "/v", v);
    writeParticleVec3(file, "/omega", omega);
    writeParticleArray(file, "/radius", radius);
    if (extra.write) {
      writeParticleArray(file, "/material", extra.material);
      writeParticleVec3(file, "/fluid_force", extra.fluidForce);
      file.setAttribute("/material", "units", "1");
      file.setAttribute("/fluid_force", "units", "N");
    }
    if (extra.temperature) {
      writeParticleArray(file, "/temperature", extra.temperatureK);
      file.setAttribute("/temperature", "units", "K");
    }
    const std::vector<int> rank(n, dec.rank());
    writeParticleArray(file, "/rank", std::span<const int>(rank));
    // The global row index of each particle: the connectivity of N one-point cells.
    const RowRange rows = rowsOf(dec.comm(), static_cast<long long>(n));
    std::vector<std::int64_t> vertex(n);
    for (std::size_t i = 0; i < n; ++i) vertex[i] = rows.offset + static_cast<long long>(i);
    writeParticleArray(file, "/vertex", std::span<const std::int64_t>(vertex));
    file.setAttribute("/", "time_units", "s");
    for (const auto& [ds, units] :
         std::initializer_list<std::pair<const char*, const char*>>{{"/id", "1"},
                                                                    {"/x", "m"},
                                                                    {"/v", "m/s"},
                                                                    {"/omega", "rad/s"},
                                                                    {"/radius", "m"},
                                                                    {"/rank", "1"},
                                                                    {"/vertex", "1"}})
      file.setAttribute(ds, "units", units);
    file.close();
  }
  entry.attributes = {{"id", false, "/id", "Int", 8},
                      {"v", true, "/v"},
                      {"omega", true, "/omega"},
                      {"radius", false, "/radius"},
                      {"rank", false, "/rank", "Int", 4}};
  if (extra.write) {
    entry.attributes.push_back({"material", false, "/material", "Int", 4});
    entry.attributes.push_back({"fluid_force", true, "/fluid_force"});
  }
  if (extra.temperature) entry.attributes.push_back({"temperature", false, "/temperature"});
  particleSeries_.add(std::move(entry));
  particleSeries_.write(dec.comm(), (std::filesystem::path(opt_.dir) / "particles.xmf").string());
  return path;
}

}  // namespace coloc
