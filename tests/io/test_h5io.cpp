// Parallel HDF5 I/O: fields and particle arrays written from 1-4 ranks with uneven splits are read
// back exactly (same and other decompositions, other rank counts), attributes, the XDMF index,
// the output writer, and the collective error path (every rank gets coloc::Error, no hang, no
// half-written file).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "coloc/core/error.hpp"
#include "coloc/io/h5io.hpp"
#include "coloc/io/output.hpp"

using namespace coloc;
namespace fs = std::filesystem;

namespace {

constexpr double kSentinel = -7.0;

/// A scratch folder shared by the ranks (made by rank 0, removed at the end).
class ScratchDir : public testing::Environment {
 public:
  void SetUp() override {
    const Comm w = Comm::world();
    std::string d;
    if (w.isRoot()) {
      std::string tmpl = (fs::temp_directory_path() / "coloc_io_XXXXXX").string();
      if (char* p = mkdtemp(tmpl.data())) d = p;
    }
    path() = w.broadcast(d);
    ASSERT_FALSE(path().empty());
  }
  void TearDown() override {
    const Comm w = Comm::world();
    w.barrier();
    if (w.isRoot()) {
      std::error_code ec;
      fs::remove_all(path(), ec);
    }
  }
  static std::string& path() {
    static std::string p;
    return p;
  }
};
[[maybe_unused]] testing::Environment* const kScratch =
    testing::AddGlobalTestEnvironment(new ScratchDir);

std::string scratch(const std::string& name) {
  return (fs::path(ScratchDir::path()) / name).string();
}

GlobalGrid grid(std::array<bool, 3> periodic = {false, false, false}) {
  GlobalGrid g;
  g.origin = {0.5, -1.0, 2.0};
  g.length = {1.1, 0.6, 0.5};
  g.cells = {11, 6, 5};
  g.periodic = periodic;
  return g;
}

/// A value per global index, distinct everywhere, exactly representable.
double code(Int3 gi, int comp = 0) {
  return 1.0 + gi[0] + 100.0 * gi[1] + 10000.0 * gi[2] + 0.25 * comp;
}

/// Uneven cuts along every axis that has more than one block (a different split from uniform).
Decomposition unevenDecomposition(const Comm& comm, const GlobalGrid& g) {
  const auto base = Decomposition::uniform(comm, g);
  std::array<std::vector<int>, 3> cuts;
  for (int d = 0; d < 3; ++d) {
    const int p = base.dims()[d];
    cuts[d].push_back(0);
    // block b gets 1 cell, except the last which gets the rest
    for (int b = 1; b < p; ++b) cuts[d].push_back(b);
    cuts[d].push_back(g.cells[d]);
  }
  return Decomposition::fromCuts(comm, g, cuts);
}

CellField filledCell(const Decomposition& dec, int ghost, int comp = 0) {
  CellField f(cellLayout(dec, ghost), kSentinel);
  forEach(f.interior(), [&](int i, int j, int k) {
    f(i, j, k) = code({dec.lo()[0] + i, dec.lo()[1] + j, dec.lo()[2] + k}, comp);
  });
  return f;
}

/// Owned cells equal the code, every ghost still holds the sentinel.
int countCellMismatches(const Decomposition& dec, const CellField& f, int comp = 0) {
  int bad = 0;
  forEach(f.allocated(), [&](int i, int j, int k) {
    const bool owned = f.interior().contains(i, j, k);
    const double expect =
        owned ? code({dec.lo()[0] + i, dec.lo()[1] + j, dec.lo()[2] + k}, comp) : kSentinel;
    if (f(i, j, k) != expect && bad++ < 3)
      ADD_FAILURE() << "cell (" << i << "," << j << "," << k << ") on rank " << dec.rank() << ": "
                    << f(i, j, k) << " expected " << expect;
  });
  return bad;
}

/// A sub-communicator of the first `n` ranks (MPI_COMM_NULL on the others).
MPI_Comm firstRanks(int n) {
  const Comm w = Comm::world();
  MPI_Comm c = MPI_COMM_NULL;
  MPI_Comm_split(w.raw(), w.rank() < n ? 0 : MPI_UNDEFINED, w.rank(), &c);
  return c;
}

// ---- particles: rank r owns count(r) items; the value of an item is a function of (r, i) ------

long long particleCount(int r, int size) {
  if (size > 1 && r == 1) return 0;  // a rank without particles
  return 3 + (5 * r) % 4;
}
std::int64_t particleId(int r, long long i) {
  return (std::int64_t{1} << 40) + 1000 * r + i;
}
double particleValue(int r, long long i, int c) {
  return 0.5 * r + 0.001 * static_cast<double>(i) + 10.0 * c;
}

/// (rank, index) of every global row, in rank order: what the file must hold.
std::vector<std::pair<int, long long>> globalRows(int size) {
  std::vector<std::pair<int, long long>> rows;
  for (int r = 0; r < size; ++r)
    for (long long i = 0; i < particleCount(r, size); ++i) rows.emplace_back(r, i);
  return rows;
}

void writeParticles(H5File& f, const Comm& comm) {
  const long long n = particleCount(comm.rank(), comm.size());
  std::vector<double> scal(static_cast<std::size_t>(n));
  std::vector<std::int64_t> ids(scal.size());
  std::vector<int> ranks(scal.size(), comm.rank());
  std::array<std::vector<double>, 3> vec;
  for (auto& c : vec) c.resize(scal.size() + 2, kSentinel);  // longer: firstRows takes n
  for (long long i = 0; i < n; ++i) {
    const auto u = static_cast<std::size_t>(i);
    scal[u] = particleValue(comm.rank(), i, 0);
    ids[u] = particleId(comm.rank(), i);
    for (int c = 0; c < 3; ++c)
      vec[static_cast<std::size_t>(c)][u] = particleValue(comm.rank(), i, c);
  }
  writeParticleArray(f, "/part/radius", scal);
  writeParticleArray(f, "/part/id", ids);
  writeParticleArray(f, "/part/rank", ranks);
  writeParticleVec3(f, "/part/x", firstRows(vec, static_cast<std::size_t>(n)));
}

/// Read rows `rows` (any split) and compare with the global rows written by `writerSize` ranks.
void checkParticles(H5File& f, const RowRange& rows, int writerSize) {
  const auto all = globalRows(writerSize);
  ASSERT_EQ(rows.total, static_cast<long long>(all.size()));
  const auto scal = readParticleArray<double>(f, "/part/radius", rows);
  const auto ids = readParticleArray<std::int64_t>(f, "/part/id", rows);
  const auto ranks = readParticleArray<int>(f, "/part/rank", rows);
  const auto vec = readParticleVec3(f, "/part/x", rows);
  ASSERT_EQ(static_cast<long long>(scal.size()), rows.count);
  for (long long k = 0; k < rows.count; ++k) {
    const auto [r, i] = all[static_cast<std::size_t>(rows.offset + k)];
    const auto u = static_cast<std::size_t>(k);
    EXPECT_EQ(scal[u], particleValue(r, i, 0));
    EXPECT_EQ(ids[u], particleId(r, i));
    EXPECT_EQ(ranks[u], r);
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(vec[static_cast<std::size_t>(c)][u], particleValue(r, i, c));
  }
}

}  // namespace

TEST(H5Io, CellFieldRoundTripOnUnevenBlocks) {
  const Comm w = Comm::world();
  const auto g = grid();
  const auto dec = unevenDecomposition(w, g);
  const std::string path = scratch("cells.h5");
  {
    H5File f = H5File::create(dec.comm(), path);
    EXPECT_FALSE(fs::exists(path)) << "the file appears only at close()";
    writeCellField(f, "/a/b/p", dec, filledCell(dec, 1));
    writeCellVector(f, "/u", dec, filledCell(dec, 2, 0), filledCell(dec, 2, 1),
                    filledCell(dec, 2, 2));
    f.close();
  }
  EXPECT_TRUE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  H5File f = H5File::openRead(dec.comm(), path);
  EXPECT_EQ(f.shape("/a/b/p"), (std::vector<long long>{5, 6, 11}));
  EXPECT_EQ(f.shape("/u"), (std::vector<long long>{5, 6, 11, 3}));
  EXPECT_TRUE(f.exists("/a/b"));
  EXPECT_FALSE(f.exists("/a/c/p"));
  // read back on the same decomposition (other ghost width: ghosts must stay untouched)
  CellField p(cellLayout(dec, 2), kSentinel);
  readCellField(f, "/a/b/p", dec, p);
  EXPECT_EQ(countCellMismatches(dec, p), 0);
  // and on the uniform one
  const auto uni = Decomposition::uniform(w, g);
  std::array<CellField, 3> u;
  for (auto& c : u) c = CellField(cellLayout(uni, 1), kSentinel);
  readCellVector(f, "/u", uni, u[0], u[1], u[2]);
  for (int c = 0; c < 3; ++c)
    EXPECT_EQ(countCellMismatches(uni, u[static_cast<std::size_t>(c)], c), 0);
}

TEST(H5Io, FaceComponentsOnClosedAndPeriodicAxes) {
  const Comm w = Comm::world();
  const auto g = grid({true, false, false});
  const auto dec = unevenDecomposition(w, g);
  const std::string path = scratch("faces.h5");
  {
    H5File f = H5File::create(w, path);
    for (int d = 0; d < 3; ++d) {
      Field3<double> u(faceLayout(dec, d, 1), kSentinel);
      forEach(faceOwned(dec, d), [&](int i, int j, int k) {
        u(i, j, k) = code({dec.lo()[0] + i, dec.lo()[1] + j, dec.lo()[2] + k}, d);
      });
      writeFaceComponent(f, "/u" + std::to_string(d), dec, d, u);
    }
    f.close();
  }
  H5File f = H5File::openRead(w, path);
  EXPECT_EQ(f.shape("/u0"), (std::vector<long long>{5, 6, 11}));  // periodic x: N faces
  EXPECT_EQ(f.shape("/u1"), (std::vector<long long>{5, 7, 11}));
  EXPECT_EQ(f.shape("/u2"), (std::vector<long long>{6, 6, 11}));
  const auto uni = Decomposition::uniform(w, g);
  for (int d = 0; d < 3; ++d) {
    Field3<double> u(faceLayout(uni, d, 1), kSentinel);
    readFaceComponent(f, "/u" + std::to_string(d), uni, d, u);
    const IndexBox owned = faceOwned(uni, d);
    int bad = 0;
    forEach(u.allocated(), [&](int i, int j, int k) {
      const double expect = owned.contains(i, j, k)
                                ? code({uni.lo()[0] + i, uni.lo()[1] + j, uni.lo()[2] + k}, d)
                                : kSentinel;
      if (u(i, j, k) != expect) ++bad;
    });
    EXPECT_EQ(bad, 0) << "component " << d;
  }
}

TEST(H5Io, ParticleArraysWithUnevenAndEmptyRanks) {
  const Comm w = Comm::world();
  const std::string path = scratch("particles.h5");
  {
    H5File f = H5File::create(w, path);
    writeParticles(f, w);
    f.close();
  }
  const auto total = static_cast<long long>(globalRows(w.size()).size());
  H5File f = H5File::openRead(w, path);
  EXPECT_EQ(f.shape("/part/x"), (std::vector<long long>{total, 3}));
  EXPECT_EQ(f.shape("/part/id"), (std::vector<long long>{total}));
  const RowRange mine = rowsOf(w, particleCount(w.rank(), w.size()));
  EXPECT_EQ(mine.total, total);
  checkParticles(f, mine, w.size());                // each rank its own rows back
  checkParticles(f, evenRows(w, total), w.size());  // an even split (restart)
}

TEST(H5Io, NoParticlesAtAll) {
  const Comm w = Comm::world();
  const std::string path = scratch("empty.h5");
  {
    H5File f = H5File::create(w, path);
    writeParticleArray(f, "/id", std::span<const std::int64_t>());
    writeParticleVec3(f, "/x", Vec3Span{});
    f.close();
  }
  H5File f = H5File::openRead(w, path);
  EXPECT_EQ(f.shape("/id"), (std::vector<long long>{0}));
  EXPECT_EQ(f.shape("/x"), (std::vector<long long>{0, 3}));
  EXPECT_TRUE(readParticleArray<std::int64_t>(f, "/id", evenRows(w, 0)).empty());
  EXPECT_TRUE(readParticleVec3(f, "/x", evenRows(w, 0))[2].empty());
}

TEST(H5Io, RestartOnOtherRankCounts) {
  // Written by every rank, read by fewer (size - 1, at least 1); then written by the fewer and
  // read by every rank: the same global arrays each way.
  const Comm w = Comm::world();
  const int fewer = std::max(1, w.size() - 1);
  const auto g = grid({false, true, false});
  const std::string big = scratch("restart_all.h5"), small = scratch("restart_few.h5");
  {
    const auto dec = unevenDecomposition(w, g);
    H5File f = H5File::create(w, big);
    writeCellField(f, "/p", dec, filledCell(dec, 1));
    writeParticles(f, w);
    f.close();
  }
  MPI_Comm sub = firstRanks(fewer);
  if (sub != MPI_COMM_NULL) {
    const Comm c(sub);
    const auto dec = Decomposition::uniform(c, g);
    {
      H5File f = H5File::openRead(c, big);
      CellField p(cellLayout(dec, 1), kSentinel);
      readCellField(f, "/p", dec, p);
      EXPECT_EQ(countCellMismatches(dec, p), 0);
      const auto total = f.shape("/part/id")[0];
      checkParticles(f, evenRows(c, total), w.size());
      f.close();
    }
    H5File f = H5File::create(c, small);
    writeCellField(f, "/p", dec, filledCell(dec, 2));
    writeParticles(f, c);
    f.close();
  }
  const auto dec = unevenDecomposition(w, g);
  H5File f = H5File::openRead(w, small);
  CellField p(cellLayout(dec, 1), kSentinel);
  readCellField(f, "/p", dec, p);
  EXPECT_EQ(countCellMismatches(dec, p), 0);
  checkParticles(f, evenRows(w, f.shape("/part/id")[0]), fewer);
  f.close();
  if (sub != MPI_COMM_NULL) MPI_Comm_free(&sub);
}

TEST(H5Io, Attributes) {
  const Comm w = Comm::world();
  const std::string path = scratch("attrs.h5");
  {
    H5File f = H5File::create(w, path);
    f.createGroup("/g/h");
    f.createGroup("/g/h");  // exists: no error
    f.setAttribute("/", "time", 0.125);
    f.setAttribute("/", "step", 42);
    f.setAttribute("/", "big", std::int64_t{1} << 50);
    f.setAttribute("/g/h", "name", "hello");
    f.setAttribute("/g/h", "empty", std::string());
    const std::vector<double> v{1.5, -2.5, 3.0};
    f.setAttribute("/g", "vec", v);
    f.setAttribute("/", "step", 43);  // replaced
    f.close();
  }
  H5File f = H5File::openRead(w, path);
  EXPECT_EQ(f.attributeDouble("/", "time"), 0.125);
  EXPECT_EQ(f.attributeInt("/", "step"), 43);
  EXPECT_EQ(f.attributeInt("/", "big"), 1LL << 50);
  EXPECT_EQ(f.attributeString("/g/h", "name"), "hello");
  EXPECT_EQ(f.attributeString("/g/h", "empty"), "");
  EXPECT_EQ(f.attributeDoubles("/g", "vec"), (std::vector<double>{1.5, -2.5, 3.0}));
  EXPECT_THROW(f.attributeDouble("/", "nope"), Error);
  EXPECT_THROW(f.attributeInt("/g/h", "name"), Error);
  EXPECT_THROW(f.setAttribute("/", "x", 1.0), Error);  // read-only
}

TEST(H5Io, ErrorsReachEveryRankWithoutHangs) {
  const Comm w = Comm::world();
  const auto g = grid();
  const auto dec = Decomposition::uniform(w, g);
  // a file in a missing folder, and under a regular file (unwritable even for root)
  const std::string plain = scratch("plain_file");
  if (w.isRoot()) std::ofstream(plain) << "x";
  w.barrier();
  for (const std::string& bad : {scratch("missing/dir/out.h5"), plain + "/out.h5"}) {
    try {
      H5File::create(w, bad);
      ADD_FAILURE() << "created " << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("cannot create"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(H5File::openRead(w, scratch("nonexistent.h5")), Error);
  EXPECT_THROW(OutputWriter(dec, OutputOptions{1, true, true, plain + "/sub"}), Error);

  const std::string path = scratch("errors.h5");
  {
    H5File f = H5File::create(w, path);
    writeCellField(f, "/p", dec, filledCell(dec, 1));
    EXPECT_THROW(writeCellField(f, "/p", dec, filledCell(dec, 1)), Error);  // exists
    // a layout mismatch on rank 0 only: every rank throws, and the file stays usable
    CellField bad =
        w.isRoot() ? CellField(FieldLayout{{1, 1, 1}, 1, {0, 0, 0}}) : filledCell(dec, 1);
    EXPECT_THROW(writeCellField(f, "/q", dec, bad), Error);
    const std::vector<double> longer(3), shorter(2);
    EXPECT_THROW(writeParticleVec3(f, "/x", Vec3Span{longer, shorter, longer}), Error);
    writeCellField(f, "/r", dec, filledCell(dec, 1));
    f.close();
  }
  H5File f = H5File::openRead(w, path);
  CellField p(cellLayout(dec, 1), kSentinel);
  EXPECT_THROW(readCellField(f, "/missing", dec, p), Error);
  EXPECT_THROW(readParticleArray<std::int64_t>(f, "/p", evenRows(w, 5)), Error);  // shape, type
  GlobalGrid other = g;
  other.cells = {12, 6, 5};
  const auto decOther = Decomposition::uniform(w, other);
  CellField q(cellLayout(decOther, 1), kSentinel);
  try {
    readCellField(f, "/p", decOther, q);
    ADD_FAILURE() << "read a [5][6][11] dataset into a 12x6x5 grid";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("shape [5, 6, 11], expected [5, 6, 12]"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(writeCellField(f, "/new", dec, p), Error);  // read-only
  readCellField(f, "/r", dec, p);
  EXPECT_EQ(countCellMismatches(dec, p), 0);
}

TEST(H5Io, AbandonedFileLeavesThePreviousOneIntact) {
  const Comm w = Comm::world();
  const std::string path = scratch("atomic.h5");
  {
    H5File f = H5File::create(w, path);
    f.setAttribute("/", "version", 1);
    f.close();
  }
  try {
    H5File f = H5File::create(w, path);
    f.setAttribute("/", "version", 2);
    w.raiseIfAny(w.rank() == w.size() - 1 ? "simulated failure while writing" : "");
    f.close();
  } catch (const Error&) {
  }
  w.barrier();
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  H5File f = H5File::openRead(w, path);
  EXPECT_EQ(f.attributeInt("/", "version"), 1);
}

TEST(H5Io, XdmfIndex) {
  const auto g = grid();
  auto s = XdmfSeries::cells("fields", g);
  for (long long step : {0, 10, 20})
    s.add({0.1 * static_cast<double>(step),
           step,
           "f_" + std::to_string(step) + ".h5",
           0,
           "",
           {{"p", false, "/p"}, {"u", true, "/u"}},
           ""});
  s.add({1.0, 10, "again.h5", 0, "", {}, ""});  // a restart from step 10 replaces 10 and 20
  ASSERT_EQ(s.steps().size(), 2u);
  EXPECT_EQ(s.steps()[1].file, "again.h5");
  const std::string x = s.xml();
  EXPECT_NE(x.find("CollectionType=\"Temporal\""), std::string::npos);
  EXPECT_NE(x.find("TopologyType=\"3DCoRectMesh\" Dimensions=\"6 7 12\""), std::string::npos);
  EXPECT_NE(x.find("Dimensions=\"5 6 11 3\""), std::string::npos);
  EXPECT_NE(x.find(">2 -1 0.5<"), std::string::npos) << "origin in z y x order";
  EXPECT_NE(x.find("f_0.h5:/p"), std::string::npos);
  auto pts = XdmfSeries::particles("particles");
  pts.add({0.005, 3, "p.h5", 17, "/x", {{"id", false, "/id", "Int", 8}}, "/vertex"});
  const std::string y = pts.xml();
  // Times as the shortest text that reads back exactly (not 0.0050000000000000001).
  EXPECT_NE(y.find("<Time Value=\"0.005\"/>"), std::string::npos) << y;
  // N one-point cells with an explicit connectivity (the Xdmf3 readers make no cells without).
  EXPECT_NE(y.find("NodesPerElement=\"1\">\n     <DataItem Dimensions=\"17 1\" NumberType=\"Int\" "
                   "Precision=\"8\" Format=\"HDF\">p.h5:/vertex</DataItem>\n    </Topology>"),
            std::string::npos)
      << y;
  EXPECT_NE(y.find("TopologyType=\"Polyvertex\" NumberOfElements=\"17\""), std::string::npos);
  EXPECT_NE(
      y.find("Dimensions=\"17 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">p.h5:/x"),
      std::string::npos);
  EXPECT_NE(y.find("NumberType=\"Int\" Precision=\"8\""), std::string::npos);
}

TEST(H5Io, XdmfTimesWithoutRoundOff) {
  // Times summed step by step carry round-off (0.1 as 0.09999999999999999 after ten steps of
  // 0.01); the index shows them as a person would write them.
  double t = 0;
  for (int i = 0; i < 10; ++i) t += 0.01;
  ASSERT_NE(t, 0.1);
  auto pts = XdmfSeries::particles("particles");
  pts.add({t, 10, "a.h5", 1, "/x", {}, "/vertex"});
  pts.add({1.2499999999999731, 125, "b.h5", 1, "/x", {}, "/vertex"});
  pts.add({0.10000000000000007, 1000, "c.h5", 1, "/x", {}, "/vertex"});
  pts.add({2.5e-7, 2000, "d.h5", 1, "/x", {}, "/vertex"});
  const std::string y = pts.xml();
  EXPECT_EQ(y.find("0.0999999"), std::string::npos) << y;
  EXPECT_EQ(y.find("0.1000000"), std::string::npos) << y;
  EXPECT_NE(y.find("<Time Value=\"0.1\"/>"), std::string::npos) << y;
  EXPECT_NE(y.find("<Time Value=\"1.25\"/>"), std::string::npos) << y;
  EXPECT_NE(y.find("<Time Value=\"2.5e-07\"/>"), std::string::npos) << y;
}

TEST(H5Io, OutputWriterSeries) {
  const Comm w = Comm::world();
  const auto g = grid();
  const auto dec = unevenDecomposition(w, g);
  OutputOptions opt{5, true, true, scratch("series/out")};
  OutputWriter out(dec, opt);
  EXPECT_TRUE(fs::is_directory(opt.dir));
  EXPECT_TRUE(out.due(0));
  EXPECT_TRUE(out.due(10));
  EXPECT_FALSE(out.due(7));
  EXPECT_EQ(OutputWriter::fileName("fields", 42), "fields_000042.h5");
  EXPECT_EQ(OutputWriter::fileName("fields", 12345678), "fields_12345678.h5");
  const auto p = filledCell(dec, 1);
  const std::array<CellField, 3> u{filledCell(dec, 1, 0), filledCell(dec, 1, 1),
                                   filledCell(dec, 1, 2)};
  const long long n = particleCount(w.rank(), w.size());
  std::vector<std::int64_t> ids(static_cast<std::size_t>(n), 7);
  std::array<std::vector<double>, 3> x;
  for (auto& c : x) c.assign(static_cast<std::size_t>(n), 0.5);
  const std::vector<double> r(static_cast<std::size_t>(n), 0.01);
  const std::vector<int> mat(static_cast<std::size_t>(n), 1 + w.rank());
  std::array<std::vector<double>, 3> ff;
  for (int d = 0; d < 3; ++d) ff[d].assign(static_cast<std::size_t>(n), 1e-6 * (d + 1));
  const std::vector<double> tempK(static_cast<std::size_t>(n), 300.0 + w.rank());
  for (long long step : {0, 5}) {
    const auto fp = out.writeFields(
        step, 0.01 * static_cast<double>(step),
        {OutputField::scalar("p", p, "m^2/s^2"), OutputField::vector("u", u, "m/s")});
    EXPECT_EQ(fp, opt.dir + "/fields_00000" + std::to_string(step) + ".h5");
    // the optional columns: material and the fluid's force (at step 5 only)
    ParticleExtraColumns extra{step == 5, mat, firstRows(ff, ids.size())};
    extra.temperature = step == 5;  // particles.heat's temperature (K)
    extra.temperatureK = tempK;
    out.writeParticles(step, 0.01 * static_cast<double>(step), ids, firstRows(x, ids.size()),
                       firstRows(x, ids.size()), firstRows(x, ids.size()), r, extra);
  }
  EXPECT_THROW(out.writeFields(6, 0.0, {OutputField::scalar("p", p), OutputField::scalar("p", p)}),
               Error);
  EXPECT_THROW(out.writeFields(6, 0.0, {OutputField::scalar("rank", p)}), Error);
  EXPECT_EQ(out.fieldSeries().steps().size(), 2u);
  EXPECT_EQ(out.particleSeries().steps().back().count,
            static_cast<long long>(globalRows(w.size()).size()));
  w.barrier();
  for (const char* f : {"fields.xmf", "particles.xmf", "fields_000005.h5", "particles_000000.h5"})
    EXPECT_TRUE(fs::exists(fs::path(opt.dir) / f)) << f;
  EXPECT_FALSE(fs::exists(fs::path(opt.dir) / "fields.xmf.tmp"));
  H5File f = H5File::openRead(w, opt.dir + "/fields_000005.h5");
  EXPECT_EQ(f.attributeInt("/", "step"), 5);
  EXPECT_EQ(f.attributeDouble("/", "time"), 0.01 * 5.0);
  CellField back(cellLayout(dec, 1), kSentinel);
  readCellField(f, "/p", dec, back);
  EXPECT_EQ(countCellMismatches(dec, back), 0);
  EXPECT_EQ(f.attributeString("/p", "units"), "m^2/s^2");
  {
    // /rank: the writer's own field, the owner of every cell (the partition in ParaView).
    CellField owner(cellLayout(dec, 1), -1.0);
    readCellField(f, "/rank", dec, owner);
    long long wrong = 0;
    forEach(IndexBox{{0, 0, 0}, dec.cells()},
            [&](int i, int j, int k) { wrong += owner(i, j, k) != static_cast<double>(w.rank()); });
    EXPECT_EQ(wrong, 0);
    EXPECT_EQ(f.attributeString("/rank", "units"), "1");
  }
  EXPECT_EQ(f.attributeString("/u", "units"), "m/s");
  EXPECT_EQ(f.attributeString("/", "time_units"), "s");
  {
    // The vertex list is the global row index 0..N-1 (the cells of the XDMF topology).
    H5File pf = H5File::openRead(w, opt.dir + "/particles_000005.h5");
    const RowRange rows = rowsOf(w, n);
    const auto vertex = readParticleArray<std::int64_t>(pf, "/vertex", rows);
    ASSERT_EQ(vertex.size(), static_cast<std::size_t>(n));
    for (std::size_t i = 0; i < vertex.size(); ++i)
      EXPECT_EQ(vertex[i], rows.offset + static_cast<long long>(i));
    EXPECT_EQ(pf.attributeString("/v", "units"), "m/s");
    EXPECT_EQ(pf.attributeString("/x", "units"), "m");
    // material and fluid_force, with their units, and ParaView sees them in the XDMF
    const auto m = readParticleArray<int>(pf, "/material", rows);
    ASSERT_EQ(m.size(), static_cast<std::size_t>(n));
    for (int v : m) EXPECT_EQ(v, 1 + w.rank());
    EXPECT_EQ(pf.attributeString("/fluid_force", "units"), "N");
    EXPECT_EQ(pf.attributeString("/material", "units"), "1");
    const auto f = readParticleVec3(pf, "/fluid_force", rows);
    for (int d = 0; d < 3; ++d)
      for (double v : f[d]) EXPECT_EQ(v, 1e-6 * (d + 1));
    const auto tk = readParticleArray<double>(pf, "/temperature", rows);
    ASSERT_EQ(tk.size(), static_cast<std::size_t>(n));
    for (double v : tk) EXPECT_EQ(v, 300.0 + w.rank());
    EXPECT_EQ(pf.attributeString("/temperature", "units"), "K");
  }
  {
    // step 0 was written without them: its file has no such datasets
    H5File p0 = H5File::openRead(w, opt.dir + "/particles_000000.h5");
    EXPECT_FALSE(p0.exists("/fluid_force"));
    EXPECT_FALSE(p0.exists("/material"));
    EXPECT_FALSE(p0.exists("/temperature"));
  }
  if (w.rank() == 0) {
    std::ifstream xmf(opt.dir + "/particles.xmf");
    const std::string text((std::istreambuf_iterator<char>(xmf)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("Name=\"fluid_force\""), std::string::npos);
    EXPECT_NE(text.find("Name=\"material\""), std::string::npos);
    EXPECT_NE(text.find("Name=\"temperature\""), std::string::npos);
  }
  // disabled series write nothing
  OutputWriter off(dec, OutputOptions{0, false, false, scratch("never")});
  EXPECT_EQ(off.writeFields(1, 0.0, {OutputField::scalar("p", p)}), "");
  EXPECT_FALSE(off.due(0));
  EXPECT_FALSE(fs::exists(scratch("never")));
}
