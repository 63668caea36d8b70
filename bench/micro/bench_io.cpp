// Parallel HDF5 I/O through coloc's h5io: collective write (create NAME.tmp, write, close, rename)
// and read of an N^3 cell field, and of the particle arrays of the output (id, x, v, omega,
// radius). Iterations are fixed so that every rank runs the same number; the time is the slowest
// rank's (manual time). Reported bytes/s = bytes of the global dataset(s) per second, the
// figure to compare with the file system's bandwidth. Reads come from the page cache when the
// file was just written. Files go to $COLOC_BENCH_DIR (default: the system temp folder) and are
// removed at the end.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>

#include "coloc/io/h5io.hpp"

namespace {

std::string benchFile(const char* name) {
  const char* dir = std::getenv("COLOC_BENCH_DIR");
  const auto base =
      dir && *dir ? std::filesystem::path(dir) : std::filesystem::temp_directory_path();
  return (base / (std::string("coloc_bench_io_") + name + ".h5")).string();
}

coloc::Decomposition cube(int n) {
  coloc::GlobalGrid g;
  g.cells = {n, n, n};
  return coloc::Decomposition::uniform(coloc::Comm::world(), g);
}

void removeFile(const coloc::Comm& comm, const std::string& path) {
  comm.barrier();
  if (comm.isRoot()) std::filesystem::remove(path);
}

template <class F>
double timed(const coloc::Comm& comm, F&& f) {
  comm.barrier();
  const double t0 = MPI_Wtime();
  f();
  return comm.max(MPI_Wtime() - t0);
}

void BM_WriteCellField(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto dec = cube(n);
  coloc::CellField f(coloc::cellLayout(dec, 1), 1.0);
  coloc::forEach(f.interior(), [&](int i, int j, int k) { f(i, j, k) = i + 0.5 * j + 0.25 * k; });
  const std::string path = benchFile("cells");
  const auto bytes = static_cast<std::int64_t>(dec.grid().cellCount() * 8);
  for (auto _ : state) {
    state.SetIterationTime(timed(dec.comm(), [&] {
      auto file = coloc::H5File::create(dec.comm(), path);
      coloc::writeCellField(file, "/p", dec, f);
      file.close();
    }));
  }
  state.SetBytesProcessed(state.iterations() * bytes);
  state.counters["ranks"] = dec.size();
  state.counters["MB_per_write"] = static_cast<double>(bytes) / 1e6;
  removeFile(dec.comm(), path);
}

void BM_ReadCellField(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto dec = cube(n);
  coloc::CellField f(coloc::cellLayout(dec, 1), 1.0);
  const std::string path = benchFile("cells_read");
  {
    auto file = coloc::H5File::create(dec.comm(), path);
    coloc::writeCellField(file, "/p", dec, f);
    file.close();
  }
  const auto bytes = static_cast<std::int64_t>(dec.grid().cellCount() * 8);
  for (auto _ : state) {
    state.SetIterationTime(timed(dec.comm(), [&] {
      auto file = coloc::H5File::openRead(dec.comm(), path);
      coloc::readCellField(file, "/p", dec, f);
    }));
  }
  state.SetBytesProcessed(state.iterations() * bytes);
  state.counters["ranks"] = dec.size();
  removeFile(dec.comm(), path);
}

void BM_WriteParticles(benchmark::State& state) {
  const auto comm = coloc::Comm::world();
  const auto total = static_cast<long long>(state.range(0));
  const auto rows = coloc::evenRows(comm, total);
  const auto n = static_cast<std::size_t>(rows.count);
  std::vector<std::int64_t> id(n);
  std::array<std::vector<double>, 3> x;
  for (auto& c : x) c.assign(n, 0.5);
  std::vector<double> radius(n, 1e-3);
  for (std::size_t i = 0; i < n; ++i) id[i] = rows.offset + static_cast<long long>(i);
  const std::string path = benchFile("particles");
  const auto v3 = coloc::firstRows(x, n);
  for (auto _ : state) {
    state.SetIterationTime(timed(comm, [&] {
      auto file = coloc::H5File::create(comm, path);
      coloc::writeParticleArray(file, "/id", id);
      coloc::writeParticleVec3(file, "/x", v3);
      coloc::writeParticleVec3(file, "/v", v3);
      coloc::writeParticleVec3(file, "/omega", v3);
      coloc::writeParticleArray(file, "/radius", radius);
      file.close();
    }));
  }
  const std::int64_t bytes = total * (8 + 3 * 24 + 8);  // id, x, v, omega, radius
  state.SetBytesProcessed(state.iterations() * bytes);
  state.counters["ranks"] = comm.size();
  removeFile(comm, path);
}

}  // namespace

BENCHMARK(BM_WriteCellField)
    ->Arg(64)
    ->Arg(128)
    ->Iterations(10)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadCellField)
    ->Arg(64)
    ->Arg(128)
    ->Iterations(10)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WriteParticles)
    ->Arg(1 << 20)
    ->Iterations(5)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
