// coloc/partition/box_halo.hpp — halos on a layout of general boxes (partition/tiled.hpp).
//
// On a tiled layout a box has any number of neighbours: every box that touches its ghost region
// (across a face, an edge or a corner, or across a periodic face: a box may be its own periodic
// image). The ghost region of rank r is cut into pieces, each the intersection of the region
// (mapped into the domain by the periodic shift) with one owner's box:
//
//   owner   the rank that owns the values (a piece of rank r's own box shifted by a period is a
//           piece too: r copies to itself);
//   src     their global indices at the owner;
//   shift   r's (extended) global index = src + shift (a multiple of the period, or 0);
//   wall    -1 / +1 along an axis where the piece lies beyond the low / high non-periodic wall.
//           Its owner is the box holding the wall cells next to it, and src names the owner's
//           own ghosts there (what the Cartesian plan's staged sweeps carry into edges and
//           corners beyond a wall). A piece of r's own wall ghosts (owner r, shift 0) moves
//           nothing in gather and is folded in scatterSum.
//
// Indices of a staggered axis (face component d) are faces: face f belongs to the owner of cell
// f, face N_d of a non-periodic axis to the owner of cell N_d - 1 (decomposition.hpp's rule).
// The order of the pieces is fixed (z, y, x segments of the region, then owners ascending), so
// the sender and the receiver enumerate the same rows without telling each other: BoxHaloPlan
// builds its CommPlan from counts both sides compute (no communication at build).
//
//   gather()      owner values -> ghosts, one message per neighbour (no staged sweeps).
//   scatterSum()  ghost contributions -> owners, added in a fixed order, then the sent ghosts
//                 are zeroed; at a non-periodic wall Fold::Mirror adds ghost layer -1-m onto
//                 cell min(m, N-1) (and N+m onto max(N-1-m, 0)) of a non-staggered axis, Keep
//                 leaves the contribution in the owner's ghost beyond the wall (HaloPlan's
//                 semantics).
#pragma once

#include <span>
#include <vector>

#include "coloc/core/timers.hpp"
#include "coloc/partition/comm_plan.hpp"
#include "coloc/partition/field.hpp"
#include "coloc/partition/halo.hpp"
#include "coloc/partition/tiled.hpp"

namespace coloc {

struct HaloPiece {
  int owner = 0;
  IndexBox src;
  Int3 shift{0, 0, 0};
  Int3 wall{0, 0, 0};
  bool selfWall(int r) const {
    return owner == r && shift == Int3{0, 0, 0};  // r's own ghosts beyond a wall
  }
};

/// The ghost region of rank r (ghost layers, staggering) as pieces, in the fixed order.
std::vector<HaloPiece> haloPieces(const BoxLayout& l, int r, int ghost, Int3 stagger = {0, 0, 0});

/// Owners of r's ghost pieces other than r's own wall ghosts, ascending, without repeats (r
/// itself where it is its own periodic image).
std::vector<int> haloNeighbours(const BoxLayout& l, int r, int ghost, Int3 stagger = {0, 0, 0});

/// Cells (values of one field) rank r receives from other ranks in one gather.
long long haloRemoteCells(const BoxLayout& l, int r, int ghost, Int3 stagger = {0, 0, 0});

class BoxHaloPlan {
 public:
  BoxHaloPlan() = default;
  /// Rank comm.rank() owns l.box[comm.rank()]; `layout` is its field layout (n must be the box's
  /// size): its ghost width and staggering say which ghosts move. `storage` is the layout of the
  /// fields the plan is applied to (the same by default; it may keep more ghost layers than move,
  /// as the coupling's one-layer plan on the fluid's two-layer fields). Throws ConfigError when a
  /// box is thinner than the ghost width along an axis where it has neighbours. No
  /// communication.
  BoxHaloPlan(const Comm& comm, const BoxLayout& l, const FieldLayout& layout);
  BoxHaloPlan(const Comm& comm, const BoxLayout& l, const FieldLayout& layout,
              const FieldLayout& storage);

  const FieldLayout& layout() const { return layout_; }
  const FieldLayout& storage() const { return storage_; }
  const std::vector<int>& neighbours() const { return neighbours_; }

  void gather(std::span<Field3<double>* const> fields, Timers* timers = nullptr,
              Exchange kind = Exchange::IntraPhysics, Traffic traffic = Traffic::Auto);
  void gather(Field3<double>& f, Timers* timers = nullptr, Exchange kind = Exchange::IntraPhysics,
              Traffic traffic = Traffic::Auto) {
    Field3<double>* p = &f;
    gather(std::span<Field3<double>* const>(&p, 1), timers, kind, traffic);
  }
  void scatterSum(std::span<Field3<double>* const> fields, Fold fold, Timers* timers = nullptr,
                  Exchange kind = Exchange::InterPhysicsRemote, Traffic traffic = Traffic::Auto);
  void scatterSum(Field3<double>& f, Fold fold, Timers* timers = nullptr,
                  Exchange kind = Exchange::InterPhysicsRemote, Traffic traffic = Traffic::Auto) {
    Field3<double>* p = &f;
    scatterSum(std::span<Field3<double>* const>(&p, 1), fold, timers, kind, traffic);
  }
  /// Bytes this rank sends to other ranks in one gather of one field.
  long long bytesPerGather() const { return bytesPerGather_; }

 private:
  void requireStorage(std::span<Field3<double>* const> fields) const;
  FieldLayout layout_, storage_;
  CommPlan plan_;
  std::vector<int> neighbours_;
  // Storage offsets (Field3::index) of this layout, in plan order:
  std::vector<std::ptrdiff_t> exportAt_;  // gather: values sent (owned, or own wall ghosts)
  std::vector<std::ptrdiff_t> mirrorAt_;  // scatterSum Mirror: where each export row is added
  std::vector<std::ptrdiff_t> importAt_;  // ghosts received / sent back
  std::vector<std::ptrdiff_t> foldFrom_, foldTo_;  // own wall ghosts and their mirror cells
  std::vector<double> recv_, sendBack_;
  long long bytesPerGather_ = 0;
};

}  // namespace coloc
