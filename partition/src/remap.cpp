#include "coloc/partition/remap.hpp"

#include <algorithm>
#include <vector>

#include "coloc/core/error.hpp"
#include "coloc/partition/comm_plan.hpp"

namespace coloc {

namespace {

IndexBox intersect(const IndexBox& a, const IndexBox& b) {
  IndexBox c;
  for (int d = 0; d < 3; ++d) {
    c.lo[d] = std::max(a.lo[d], b.lo[d]);
    c.hi[d] = std::max(c.lo[d], std::min(a.hi[d], b.hi[d]));
  }
  return c;
}

}  // namespace

IndexBox ownedGlobalBox(const Decomposition& dec, int r, int stagger) {
  IndexBox b{dec.loOf(r), dec.hiOf(r)};
  const GlobalGrid& g = dec.grid();
  if (stagger >= 0 && !g.periodic[stagger] && b.hi[stagger] == g.cells[stagger]) b.hi[stagger] += 1;
  return b;
}

void remapFields(const Decomposition& from, std::span<const Field3<double>* const> src,
                 const Decomposition& to, std::span<Field3<double>* const> dst, int stagger) {
  if (src.size() != dst.size() || src.empty())
    throw Error("remapFields: as many destination fields as source fields expected");
  const Comm& comm = from.comm();
  const int size = comm.size(), me = comm.rank();
  if (to.size() != size) throw Error("remapFields: the two decompositions differ in ranks");
  const int w = static_cast<int>(src.size());
  const auto uw = static_cast<std::size_t>(w);
  const IndexBox mine = ownedGlobalBox(from, me, stagger);
  const IndexBox target = ownedGlobalBox(to, me, stagger);
  std::vector<int> sendCounts(static_cast<std::size_t>(size)), recvCounts(sendCounts.size());
  std::vector<IndexBox> out(sendCounts.size()), in(sendCounts.size());
  long long nSend = 0;
  for (int r = 0; r < size; ++r) {
    const auto u = static_cast<std::size_t>(r);
    out[u] = intersect(mine, ownedGlobalBox(to, r, stagger));
    in[u] = intersect(ownedGlobalBox(from, r, stagger), target);
    sendCounts[u] = static_cast<int>(out[u].volume());
    recvCounts[u] = static_cast<int>(in[u].volume());
    nSend += sendCounts[u];
  }
  // Rows in destination order, each box x fastest; w values a row (one per field).
  std::vector<double> rows(static_cast<std::size_t>(nSend) * uw);
  std::size_t q = 0;
  const Int3 lo = from.lo();
  for (const IndexBox& b : out)
    forEach(b, [&](int i, int j, int k) {
      for (const Field3<double>* f : src) rows[q++] = (*f)(i - lo[0], j - lo[1], k - lo[2]);
    });
  CommPlan plan = CommPlan::fromCounts(comm, std::move(sendCounts), std::move(recvCounts));
  std::vector<double> got(plan.importCount() * uw);
  plan.forward(rows, w, got);
  q = 0;
  const Int3 tlo = to.lo();
  for (const IndexBox& b : in)
    forEach(b, [&](int i, int j, int k) {
      for (Field3<double>* f : dst) (*f)(i - tlo[0], j - tlo[1], k - tlo[2]) = got[q++];
    });
}

}  // namespace coloc
