// Cell fields, face components and particle arrays as collective slabs of global datasets.
// Layout and rules: coloc/io/h5io.hpp.
#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "coloc/io/h5io.hpp"
#include "h5detail.hpp"

namespace coloc {
using namespace h5;
namespace {

// ---- fields -------------------------------------------------------------------------------------

/// The slab of an owned box `owned` (local indices) of a global array of `globalN` entries per
/// axis, with `comps` interleaved components ([z][y][x] or [z][y][x][comps]).
Slab fieldSlab(const Decomposition& dec, const IndexBox& owned, Int3 globalN, int comps) {
  Slab s;
  s.rank = comps > 1 ? 4 : 3;
  for (int a = 0; a < 3; ++a) {
    const int d = 2 - a;  // z, y, x
    const auto i = static_cast<std::size_t>(a);
    s.global[i] = static_cast<hsize_t>(globalN[d]);
    s.start[i] = static_cast<hsize_t>(dec.lo()[d] + owned.lo[d]);
    s.count[i] = static_cast<hsize_t>(std::max(0, owned.hi[d] - owned.lo[d]));
  }
  s.global[3] = s.count[3] = static_cast<hsize_t>(comps);
  return s;
}

std::string layoutError(const Decomposition& dec, const Field3<double>& f, Int3 stagger) {
  const auto& l = f.layout();
  if (l.n != dec.cells() || l.stagger != stagger)
    return fmt::format(
        "field layout does not match this rank's block (owned cells {}x{}x{}, block {}x{}x{})",
        l.n[0], l.n[1], l.n[2], dec.cells()[0], dec.cells()[1], dec.cells()[2]);
  return {};
}

/// Copy the owned box of the fields into buf (x fastest, components interleaved), and back.
void packBox(std::span<const Field3<double>* const> fields, const IndexBox& b,
             std::vector<double>& buf) {
  std::size_t at = 0;
  forEach(b, [&](int i, int j, int k) {
    for (const auto* f : fields) buf[at++] = (*f)(i, j, k);
  });
}
void unpackBox(std::span<Field3<double>* const> fields, const IndexBox& b,
               const std::vector<double>& buf) {
  std::size_t at = 0;
  forEach(b, [&](int i, int j, int k) {
    for (auto* f : fields) (*f)(i, j, k) = buf[at++];
  });
}

void writeBox(H5File& file, const std::string& path, const Decomposition& dec,
              std::span<const Field3<double>* const> fields, const IndexBox& owned, Int3 globalN,
              Int3 stagger) {
  std::string err;
  for (const auto* f : fields)
    if (err.empty()) err = layoutError(dec, *f, stagger);
  const Slab s = fieldSlab(dec, owned, globalN, static_cast<int>(fields.size()));
  std::vector<double> buf;
  if (err.empty()) {
    buf.resize(static_cast<std::size_t>(s.localElements()));
    packBox(fields, owned, buf);
  }
  writeSlab(file, path, Elem::F64, s, buf.data(), err);
}

void readBox(H5File& file, const std::string& path, const Decomposition& dec,
             std::span<Field3<double>* const> fields, const IndexBox& owned, Int3 globalN,
             Int3 stagger) {
  std::string err;
  for (const auto* f : fields)
    if (err.empty()) err = layoutError(dec, *f, stagger);
  const Slab s = fieldSlab(dec, owned, globalN, static_cast<int>(fields.size()));
  std::vector<double> buf(err.empty() ? static_cast<std::size_t>(s.localElements()) : 0);
  readSlab(file, path, Elem::F64, s, buf.data(), err);
  unpackBox(fields, owned, buf);
}

Int3 faceGlobal(const Decomposition& dec, int d) {
  Int3 n = dec.grid().cells;
  if (!dec.grid().periodic[d]) n[d] += 1;
  return n;
}
Int3 staggerOf(int d) {
  Int3 s{0, 0, 0};
  s[d] = 1;
  return s;
}

// ---- particles ----------------------------------------------------------------------------------

Slab rowSlab(const RowRange& r, int comps) {
  Slab s;
  s.rank = comps > 1 ? 2 : 1;
  s.global = {static_cast<hsize_t>(r.total), static_cast<hsize_t>(comps), 0, 0};
  s.start = {static_cast<hsize_t>(r.offset), 0, 0, 0};
  s.count = {static_cast<hsize_t>(r.count), static_cast<hsize_t>(comps), 0, 0};
  return s;
}

template <class T>
void writeRows(H5File& file, const std::string& path, std::span<const T> local) {
  const RowRange r = rowsOf(file.comm(), static_cast<long long>(local.size()));
  writeSlab(file, path, elemOf<T>(), rowSlab(r, 1), local.data());
}

}  // namespace

// ---- fields -------------------------------------------------------------------------------------

void writeCellField(H5File& file, const std::string& path, const Decomposition& dec,
                    const CellField& f) {
  const Field3<double>* p[1] = {&f};
  writeBox(file, path, dec, p, IndexBox{{0, 0, 0}, dec.cells()}, dec.grid().cells, {0, 0, 0});
}

void readCellField(H5File& file, const std::string& path, const Decomposition& dec, CellField& f) {
  Field3<double>* p[1] = {&f};
  readBox(file, path, dec, p, IndexBox{{0, 0, 0}, dec.cells()}, dec.grid().cells, {0, 0, 0});
}

void writeCellVector(H5File& file, const std::string& path, const Decomposition& dec,
                     const CellField& x, const CellField& y, const CellField& z) {
  const Field3<double>* p[3] = {&x, &y, &z};
  writeBox(file, path, dec, p, IndexBox{{0, 0, 0}, dec.cells()}, dec.grid().cells, {0, 0, 0});
}

void readCellVector(H5File& file, const std::string& path, const Decomposition& dec, CellField& x,
                    CellField& y, CellField& z) {
  Field3<double>* p[3] = {&x, &y, &z};
  readBox(file, path, dec, p, IndexBox{{0, 0, 0}, dec.cells()}, dec.grid().cells, {0, 0, 0});
}

void writeFaceComponent(H5File& file, const std::string& path, const Decomposition& dec, int d,
                        const Field3<double>& f) {
  const Field3<double>* p[1] = {&f};
  writeBox(file, path, dec, p, faceOwned(dec, d), faceGlobal(dec, d), staggerOf(d));
}

void readFaceComponent(H5File& file, const std::string& path, const Decomposition& dec, int d,
                       Field3<double>& f) {
  Field3<double>* p[1] = {&f};
  readBox(file, path, dec, p, faceOwned(dec, d), faceGlobal(dec, d), staggerOf(d));
}

// ---- particles ----------------------------------------------------------------------------------

void writeParticleArray(H5File& file, const std::string& path, std::span<const double> local) {
  writeRows(file, path, local);
}
void writeParticleArray(H5File& file, const std::string& path,
                        std::span<const std::int64_t> local) {
  writeRows(file, path, local);
}
void writeParticleArray(H5File& file, const std::string& path, std::span<const int> local) {
  writeRows(file, path, local);
}

void writeParticleVec3(H5File& file, const std::string& path, Vec3Span local) {
  std::string err;
  const std::size_t n = local[0].size();
  if (local[1].size() != n || local[2].size() != n)
    err = "the three components have different lengths";
  const RowRange r = rowsOf(file.comm(), err.empty() ? static_cast<long long>(n) : 0);
  std::vector<double> buf;
  if (err.empty()) {
    buf.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t c = 0; c < 3; ++c) buf[3 * i + c] = local[c][i];
  }
  writeSlab(file, path, Elem::F64, rowSlab(r, 3), buf.data(), err);
}

template <class T>
std::vector<T> readParticleArray(H5File& file, const std::string& path, const RowRange& rows) {
  std::vector<T> out(static_cast<std::size_t>(std::max(0LL, rows.count)));
  readSlab(file, path, elemOf<T>(), rowSlab(rows, 1), out.data());
  return out;
}
template std::vector<double> readParticleArray<double>(H5File&, const std::string&,
                                                       const RowRange&);
template std::vector<std::int64_t> readParticleArray<std::int64_t>(H5File&, const std::string&,
                                                                   const RowRange&);
template std::vector<int> readParticleArray<int>(H5File&, const std::string&, const RowRange&);

std::array<std::vector<double>, 3> readParticleVec3(H5File& file, const std::string& path,
                                                    const RowRange& rows) {
  const auto n = static_cast<std::size_t>(std::max(0LL, rows.count));
  std::vector<double> buf(3 * n);
  readSlab(file, path, Elem::F64, rowSlab(rows, 3), buf.data());
  std::array<std::vector<double>, 3> out;
  for (std::size_t c = 0; c < 3; ++c) {
    out[c].resize(n);
    for (std::size_t i = 0; i < n; ++i) out[c][i] = buf[3 * i + c];
  }
  return out;
}

}  // namespace coloc
