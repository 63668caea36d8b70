// The rows of a global particle array that each rank holds: no HDF5 (also in the SMPI build).
#include <algorithm>

#include "coloc/io/h5io.hpp"

namespace coloc {

RowRange rowsOf(const Comm& comm, long long localCount) {
  RowRange r;
  r.count = localCount;
  long long before = 0;
  MPI_Exscan(&localCount, &before, 1, MPI_LONG_LONG, MPI_SUM, comm.raw());
  r.offset = comm.rank() == 0 ? 0 : before;
  r.total = comm.sum(localCount);
  return r;
}

RowRange evenRows(const Comm& comm, long long total) {
  const long long p = comm.size(), me = comm.rank();
  RowRange r;
  r.total = total;
  r.offset = me * (total / p) + std::min(me, total % p);
  r.count = total / p + (me < total % p ? 1 : 0);
  return r;
}

Vec3Span firstRows(const std::array<std::vector<double>, 3>& soa, std::size_t n) {
  return {std::span<const double>(soa[0]).first(n), std::span<const double>(soa[1]).first(n),
          std::span<const double>(soa[2]).first(n)};
}

}  // namespace coloc
