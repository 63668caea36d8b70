// coloc/partition/remap.hpp — moving fields from one decomposition to another of the same grid
// (re-balancing in memory). Every rank knows both sets of blocks, so what it sends to and
// receives from each rank is the intersection of two boxes: no counts travel. The values go in
// one exchange through a CommPlan (partition/comm_plan.hpp), all fields of a staggering
// together. Owned values only: ghosts are the caller's to refresh.
#pragma once

#include <span>

#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/field.hpp"

namespace coloc {

/// Global index box of the values rank r owns in `dec`: its cells, or for a face component
/// (stagger = d) the faces [lo, hi) along d plus face N_d at a non-periodic high box face.
IndexBox ownedGlobalBox(const Decomposition& dec, int r, int stagger = -1);

/// The owned values of `src` (laid out on `from`) into `dst` (laid out on `to`), every field of
/// the same staggering (-1: cells, d: face component d). `from` and `to` share the ranks (the
/// same communicator, numbered alike). Collective.
void remapFields(const Decomposition& from, std::span<const Field3<double>* const> src,
                 const Decomposition& to, std::span<Field3<double>* const> dst, int stagger = -1);

}  // namespace coloc
