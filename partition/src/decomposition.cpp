#include "coloc/partition/decomposition.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "coloc/core/error.hpp"

namespace coloc {
namespace {
const char* kAxis[3] = {"x", "y", "z"};

/// Ownership of a communicator a decomposition creates: freed with the last copy (unless MPI is
/// already finalized).
std::shared_ptr<MPI_Comm> ownedComm(MPI_Comm* c) {
  return std::shared_ptr<MPI_Comm>(c, [](MPI_Comm* p) {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized && *p != MPI_COMM_NULL) MPI_Comm_free(p);
    delete p;
  });
}
}  // namespace

std::vector<int> Decomposition::evenCuts(int n, int p) {
  std::vector<int> c(static_cast<std::size_t>(p) + 1);
  for (int i = 0; i <= p; ++i) c[static_cast<std::size_t>(i)] = i * (n / p) + std::min(i, n % p);
  return c;
}

Int3 Decomposition::chooseDims(int size, const GlobalGrid& grid, Int3 dims, int minCells) {
  for (int d = 0; d < 3; ++d)
    if (dims[d] < 0) throw ConfigError("partition.dims", "process counts must be >= 0");
  if (size < 1) throw ConfigError("partition.dims", "the rank count must be at least 1");
  minCells = std::max(minCells, 1);
  int fixed = 1;
  for (int d = 0; d < 3; ++d)
    if (dims[d] > 0) fixed *= dims[d];
  if (size % fixed != 0)
    throw ConfigError(
        "partition.dims",
        fmt::format("the fixed process counts (product {}) do not divide the {} ranks", fixed,
                    size));
  if (dims[0] > 0 && dims[1] > 0 && dims[2] > 0) return dims;  // fully fixed: checked by uniform()
  // Legal: the even split leaves every block at least minCells cells along every axis.
  const auto legal = [&](const Int3& c) {
    for (int d = 0; d < 3; ++d)
      if (1LL * c[d] * minCells > grid.cells[d]) return false;
    return true;
  };
  // MPI_Dims_create balances the free counts; the largest count goes to the free axis with
  // the most cells so blocks stay close to cubes (fewest halo cells).
  Int3 first = dims;
  {
    std::vector<int> freeAxes;
    for (int d = 0; d < 3; ++d)
      if (dims[d] == 0) freeAxes.push_back(d);
    std::vector<int> counts(freeAxes.size(), 0);
    MPI_Dims_create(size / fixed, static_cast<int>(counts.size()), counts.data());
    std::sort(counts.begin(), counts.end(), std::greater<>());
    std::stable_sort(freeAxes.begin(), freeAxes.end(),
                     [&](int a, int b) { return grid.cells[a] > grid.cells[b]; });
    for (std::size_t i = 0; i < freeAxes.size(); ++i) first[freeAxes[i]] = counts[i];
  }
  if (legal(first)) return first;
  // That grid makes blocks too thin along an axis: among every factorisation of the rank count
  // (fixed entries kept) take the legal one with the smallest block surface (halo cells),
  // ties to the first in (x, y, z) order.
  Int3 best{0, 0, 0};
  double bestArea = std::numeric_limits<double>::infinity();
  for (int px = 1; px <= size; ++px) {
    if (size % px || (dims[0] > 0 && px != dims[0])) continue;
    for (int py = 1; py <= size / px; ++py) {
      if ((size / px) % py || (dims[1] > 0 && py != dims[1])) continue;
      const int pz = size / px / py;
      if (dims[2] > 0 && pz != dims[2]) continue;
      const Int3 c{px, py, pz};
      if (!legal(c)) continue;
      const double bx = static_cast<double>(grid.cells[0]) / px,
                   by = static_cast<double>(grid.cells[1]) / py,
                   bz = static_cast<double>(grid.cells[2]) / pz;
      const double area = bx * by + by * bz + bx * bz;
      if (area < bestArea * (1 - 1e-12)) {
        bestArea = area;
        best = c;
      }
    }
  }
  if (best[0] > 0) return best;
  throw ConfigError("partition.dims",
                    fmt::format("no process grid of {} ranks gives every block at least {} cells "
                                "along every axis (domain.cells = {} x {} x {}{}): use fewer "
                                "ranks, more cells (domain.cells) or other partition.dims",
                                size, minCells, grid.cells[0], grid.cells[1], grid.cells[2],
                                fixed > 1 ? fmt::format(", partition.dims fixes {}", fixed) : ""));
}

Decomposition Decomposition::uniform(const Comm& world, const GlobalGrid& grid, Int3 dims,
                                     int minCells) {
  const int size = world.size();
  for (int d = 0; d < 3; ++d)
    if (grid.cells[d] < 1)
      throw ConfigError("grid.cells", std::string("the number of cells along ") + kAxis[d] +
                                          " must be at least 1");
  dims = chooseDims(size, grid, dims, minCells);
  int product = dims[0] * dims[1] * dims[2];
  if (product != size)
    throw ConfigError("partition.dims", fmt::format("process grid {}x{}x{} does not match {} ranks",
                                                    dims[0], dims[1], dims[2], size));
  std::array<std::vector<int>, 3> cuts;
  for (int d = 0; d < 3; ++d) {
    if (dims[d] > grid.cells[d])
      throw ConfigError("partition.dims",
                        fmt::format("{} ranks along {} but only {} cells: each block needs a cell",
                                    dims[d], kAxis[d], grid.cells[d]));
    cuts[d] = evenCuts(grid.cells[d], dims[d]);
  }
  return fromCuts(world, grid, std::move(cuts));
}

Decomposition Decomposition::fromCuts(const Comm& world, const GlobalGrid& grid,
                                      std::array<std::vector<int>, 3> cuts) {
  Decomposition dec;
  dec.grid_ = grid;
  for (int d = 0; d < 3; ++d) {
    const auto& c = cuts[d];
    if (c.size() < 2 || c.front() != 0 || c.back() != grid.cells[d])
      throw ConfigError("partition.cuts", std::string("cuts along ") + kAxis[d] +
                                              " must run from 0 to the cell count");
    for (std::size_t i = 1; i < c.size(); ++i)
      if (c[i] <= c[i - 1])
        throw ConfigError("partition.cuts", std::string("cuts along ") + kAxis[d] +
                                                " must be strictly increasing (empty block)");
    dec.dims_[d] = static_cast<int>(c.size()) - 1;
  }
  if (dec.dims_[0] * dec.dims_[1] * dec.dims_[2] != world.size())
    throw ConfigError("partition.dims", "the process grid does not match the number of ranks");
  dec.cuts_ = std::move(cuts);
  dec.build(world);
  return dec;
}

Decomposition Decomposition::fromBoxes(const Comm& world, const GlobalGrid& grid,
                                       std::vector<Int3> lo, std::vector<Int3> hi) {
  const int P = world.size();
  if (static_cast<int>(lo.size()) != P || static_cast<int>(hi.size()) != P)
    throw ConfigError("partition.boxes", fmt::format("{} boxes for {} ranks", lo.size(), P));
  for (int r = 0; r < P; ++r)
    for (int d = 0; d < 3; ++d)
      if (lo[r][d] < 0 || hi[r][d] > grid.cells[d] || hi[r][d] <= lo[r][d])
        throw ConfigError(
            "partition.boxes",
            fmt::format("box of rank {} is empty or leaves the grid along {}", r, kAxis[d]));
  Decomposition dec;
  dec.grid_ = grid;
  dec.boxLo_ = std::move(lo);
  dec.boxHi_ = std::move(hi);
  // The tree of cut planes: a region holding several boxes is split by a plane that no box
  // crosses (the first such plane along x, then y, then z); a leaf's region must equal its box,
  // so the boxes tile the grid exactly. Built alike on every rank from the same boxes.
  std::vector<int> ranks(static_cast<std::size_t>(P));
  for (int r = 0; r < P; ++r) ranks[static_cast<std::size_t>(r)] = r;
  struct Item {
    std::vector<int> ranks;
    Int3 lo, hi;
    int node;
  };
  dec.tree_.push_back({});
  std::vector<Item> work{{std::move(ranks), Int3{0, 0, 0}, grid.cells, 0}};
  while (!work.empty()) {
    Item it = std::move(work.back());
    work.pop_back();
    const auto node = static_cast<std::size_t>(it.node);
    if (it.ranks.size() == 1) {
      const int r = it.ranks[0];
      if (dec.boxLo_[static_cast<std::size_t>(r)] != it.lo ||
          dec.boxHi_[static_cast<std::size_t>(r)] != it.hi)
        throw ConfigError("partition.boxes",
                          fmt::format("the boxes do not tile the grid (rank {})", r));
      dec.tree_[node] = {-1, 0, r, r};
      continue;
    }
    int axis = -1, plane = 0;
    for (int d = 0; d < 3 && axis < 0; ++d) {
      std::vector<std::pair<int, int>> spans;  // (lo, hi) along d
      for (int r : it.ranks)
        spans.emplace_back(dec.boxLo_[static_cast<std::size_t>(r)][d],
                           dec.boxHi_[static_cast<std::size_t>(r)][d]);
      std::sort(spans.begin(), spans.end());
      int reach = spans[0].second;  // the highest face of the boxes starting before a plane
      for (std::size_t i = 1; i < spans.size(); ++i) {
        if (spans[i].first >= reach && spans[i].first > it.lo[d]) {
          axis = d;
          plane = spans[i].first;
          break;
        }
        reach = std::max(reach, spans[i].second);
      }
    }
    if (axis < 0)
      throw ConfigError("partition.boxes",
                        "the boxes overlap or cannot be separated by cut planes");
    Item low{{}, it.lo, it.hi, 0}, high{{}, it.lo, it.hi, 0};
    low.hi[axis] = plane;
    high.lo[axis] = plane;
    for (int r : it.ranks)
      (dec.boxHi_[static_cast<std::size_t>(r)][axis] <= plane ? low : high).ranks.push_back(r);
    low.node = static_cast<int>(dec.tree_.size());
    high.node = low.node + 1;
    dec.tree_[node] = {axis, plane, low.node, high.node};
    dec.tree_.push_back({});
    dec.tree_.push_back({});
    work.push_back(std::move(low));
    work.push_back(std::move(high));
  }
  auto* c = new MPI_Comm(MPI_COMM_NULL);
  MPI_Comm_dup(world.raw(), c);
  dec.cart_ = ownedComm(c);
  dec.comm_ = Comm(*dec.cart_);
  dec.rank_ = dec.comm_.rank();
  dec.size_ = dec.comm_.size();
  dec.lo_ = dec.boxLo_[static_cast<std::size_t>(dec.rank_)];
  dec.hi_ = dec.boxHi_[static_cast<std::size_t>(dec.rank_)];
  return dec;
}

std::string Decomposition::shape() const {
  if (isTiled()) return fmt::format("{} {}", size_, size_ == 1 ? "box" : "boxes");
  return fmt::format("{}x{}x{} blocks", dims_[0], dims_[1], dims_[2]);
}

void Decomposition::requireGrid(const char* what) const {
  if (isTiled())
    throw Error(std::string("Decomposition::") + what +
                " is not defined on a tiled layout (use the box neighbours)");
}

Int3 Decomposition::dims() const {
  requireGrid("dims");
  return dims_;
}

Int3 Decomposition::coords() const {
  requireGrid("coords");
  return coords_;
}

const std::array<std::vector<int>, 3>& Decomposition::cuts() const {
  requireGrid("cuts");
  return cuts_;
}

int Decomposition::neighbour(int d, int side) const {
  requireGrid("neighbour");
  return nbr_[d][side > 0 ? 1 : 0];
}

void Decomposition::boxes(std::vector<Int3>& lo, std::vector<Int3>& hi) const {
  if (isTiled()) {
    lo = boxLo_;
    hi = boxHi_;
    return;
  }
  lo.resize(static_cast<std::size_t>(size_));
  hi.resize(static_cast<std::size_t>(size_));
  for (int r = 0; r < size_; ++r) {
    lo[static_cast<std::size_t>(r)] = loOf(r);
    hi[static_cast<std::size_t>(r)] = hiOf(r);
  }
}

void Decomposition::build(const Comm& world) {
  int periods[3] = {grid_.periodic[0], grid_.periodic[1], grid_.periodic[2]};
  auto* c = new MPI_Comm(MPI_COMM_NULL);
  MPI_Cart_create(world.raw(), 3, dims_.data(), periods, /*reorder=*/0, c);
  cart_ = ownedComm(c);
  comm_ = Comm(*cart_);
  rank_ = comm_.rank();
  size_ = comm_.size();
  MPI_Cart_coords(*cart_, rank_, 3, coords_.data());
  for (int d = 0; d < 3; ++d) {
    lo_[d] = cuts_[d][static_cast<std::size_t>(coords_[d])];
    hi_[d] = cuts_[d][static_cast<std::size_t>(coords_[d]) + 1];
    int lowN = MPI_PROC_NULL, highN = MPI_PROC_NULL;
    MPI_Cart_shift(*cart_, d, 1, &lowN, &highN);
    nbr_[d] = {lowN, highN};
  }
}

long long Decomposition::ownedCellCount() const {
  const auto n = cells();
  return 1LL * n[0] * n[1] * n[2];
}

Real3 Decomposition::blockLo() const {
  Real3 x{};
  for (int d = 0; d < 3; ++d) x[d] = grid_.origin[d] + lo_[d] * grid_.spacing(d);
  return x;
}

Real3 Decomposition::blockHi() const {
  Real3 x{};
  for (int d = 0; d < 3; ++d)
    x[d] = hi_[d] == grid_.cells[d] ? grid_.origin[d] + grid_.length[d]
                                    : grid_.origin[d] + hi_[d] * grid_.spacing(d);
  return x;
}

int Decomposition::rankOfCoords(Int3 c) const {
  requireGrid("rankOfCoords");
  int r = 0;
  MPI_Cart_rank(*cart_, c.data(), &r);
  return r;
}

Int3 Decomposition::coordsOfRank(int r) const {
  requireGrid("coordsOfRank");
  Int3 c{};
  MPI_Cart_coords(*cart_, r, 3, c.data());
  return c;
}

Int3 Decomposition::loOf(int r) const {
  if (isTiled()) return boxLo_[static_cast<std::size_t>(r)];
  const auto c = coordsOfRank(r);
  return {cuts_[0][static_cast<std::size_t>(c[0])], cuts_[1][static_cast<std::size_t>(c[1])],
          cuts_[2][static_cast<std::size_t>(c[2])]};
}

Int3 Decomposition::hiOf(int r) const {
  if (isTiled()) return boxHi_[static_cast<std::size_t>(r)];
  const auto c = coordsOfRank(r);
  return {cuts_[0][static_cast<std::size_t>(c[0]) + 1],
          cuts_[1][static_cast<std::size_t>(c[1]) + 1],
          cuts_[2][static_cast<std::size_t>(c[2]) + 1]};
}

int Decomposition::blockAlong(int d, int cell) const {
  const auto& c = cuts_[d];
  return static_cast<int>(std::upper_bound(c.begin(), c.end(), cell) - c.begin()) - 1;
}

int Decomposition::ownerOfCell(Int3 cell) const {
  Int3 b{};
  for (int d = 0; d < 3; ++d) {
    int i = cell[d];
    const int n = grid_.cells[d];
    if (grid_.periodic[d]) i = ((i % n) + n) % n;
    if (i < 0 || i >= n) return -1;
    cell[d] = i;
    if (!isTiled()) b[d] = blockAlong(d, i);
  }
  if (isTiled()) {
    const Node* node = &tree_[0];
    while (node->axis >= 0)
      node =
          &tree_[static_cast<std::size_t>(cell[node->axis] < node->plane ? node->low : node->high)];
    return node->low;
  }
  return rankOfCoords(b);
}

int Decomposition::ownerOfFace(int d, Int3 face) const {
  Int3 cell = face;
  if (!grid_.periodic[d] && face[d] == grid_.cells[d]) cell[d] = grid_.cells[d] - 1;
  return ownerOfCell(cell);
}

Int3 Decomposition::cellOfPoint(Real3 x) const {
  Int3 c{};
  for (int d = 0; d < 3; ++d) {
    const double s = (x[d] - grid_.origin[d]) / grid_.spacing(d);
    c[d] = std::clamp(static_cast<int>(std::floor(s)), 0, grid_.cells[d] - 1);
  }
  return c;
}

int Decomposition::ownerOfPoint(Real3 x) const {
  Int3 c{};
  for (int d = 0; d < 3; ++d) {
    double s = (x[d] - grid_.origin[d]) / grid_.spacing(d);
    const int n = grid_.cells[d];
    if (!std::isfinite(s)) return -1;
    if (grid_.periodic[d]) {
      s = std::fmod(s, static_cast<double>(n));
      if (s < 0) s += n;
    } else if (s < 0.0 || s > static_cast<double>(n)) {
      return -1;
    }
    c[d] = std::clamp(static_cast<int>(std::floor(s)), 0, n - 1);
  }
  return ownerOfCell(c);
}

}  // namespace coloc
