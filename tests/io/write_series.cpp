// Writes a small output series through OutputWriter for check_output.py:
//   io_write_series DIR
// Grid 7 x 5 x 4 cells, origin (0.5, -1, 2), cell size (0.2, 0.25, 0.5); outputs at steps
// 0, 5, 10 (time = 0.01 * step). Every value is a formula of the global index that
// check_output.py evaluates again:
//   p[k][j][i]      = i + 10 j + 100 k + 1000 step
//   u[k][j][i][c]   = (cell centre)_c + step
//   rank r owns n_r = (r == 1 ? 0 : 2 + 3 r) particles (in rank order in the file), particle q:
//   id = 1000 r + q + 2^40, x = (0.6 + 0.1 q, -0.9 + 0.1 r, 2.1 + 0.01 step), v = (q, r, step),
//   omega = -v, radius = 0.01 (1 + q).
#include <cstdio>
#include <filesystem>

#include "coloc/core/error.hpp"
#include "coloc/io/output.hpp"

int main(int argc, char** argv) {
  using namespace coloc;
  MPI_Init(&argc, &argv);
  int status = 0;
  {
    const Comm w = Comm::world();
    try {
      if (argc != 2) throw Error("usage: io_write_series DIR");
      const std::string dir = argv[1];
      if (w.isRoot()) std::filesystem::remove_all(dir);
      w.barrier();
      GlobalGrid g;
      g.origin = {0.5, -1.0, 2.0};
      g.length = {1.4, 1.25, 2.0};
      g.cells = {7, 5, 4};
      const auto dec = Decomposition::uniform(w, g);
      OutputWriter out(dec, OutputOptions{5, true, true, dir});
      CellField p(cellLayout(dec, 1), -1.0);
      std::array<CellField, 3> u;
      for (auto& c : u) c = CellField(cellLayout(dec, 1), -1.0);
      const int r = w.rank();
      const std::size_t n = (w.size() > 1 && r == 1) ? 0 : static_cast<std::size_t>(2 + 3 * r);
      std::vector<std::int64_t> id(n);
      std::array<std::vector<double>, 3> x, v, om;
      for (int c = 0; c < 3; ++c) x[c].resize(n), v[c].resize(n), om[c].resize(n);
      std::vector<double> radius(n);
      for (long long step = 0; step <= 10; ++step) {
        if (!out.due(step)) continue;
        const double time = 0.01 * static_cast<double>(step);
        forEach(p.interior(), [&](int i, int j, int k) {
          const Int3 gi{dec.lo()[0] + i, dec.lo()[1] + j, dec.lo()[2] + k};
          p(i, j, k) = gi[0] + 10.0 * gi[1] + 100.0 * gi[2] + 1000.0 * static_cast<double>(step);
          for (int c = 0; c < 3; ++c)
            u[c](i, j, k) = g.origin[c] + (gi[c] + 0.5) * g.spacing(c) + static_cast<double>(step);
        });
        for (std::size_t q = 0; q < n; ++q) {
          const double qd = static_cast<double>(q);
          id[q] = 1000 * r + static_cast<std::int64_t>(q) + (std::int64_t{1} << 40);
          x[0][q] = 0.6 + 0.1 * qd;
          x[1][q] = -0.9 + 0.1 * r;
          x[2][q] = 2.1 + 0.01 * static_cast<double>(step);
          const double vv[3] = {qd, double(r), static_cast<double>(step)};
          for (int c = 0; c < 3; ++c) v[c][q] = vv[c], om[c][q] = -vv[c];
          radius[q] = 0.01 * (1.0 + qd);
        }
        out.writeFields(step, time, {OutputField::scalar("p", p), OutputField::vector("u", u)});
        out.writeParticles(step, time, id, firstRows(x, n), firstRows(v, n), firstRows(om, n),
                           radius);
      }
    } catch (const std::exception& e) {
      if (w.isRoot()) std::fprintf(stderr, "io_write_series: %s\n", e.what());
      status = 1;
    }
  }
  MPI_Finalize();
  return status;
}
