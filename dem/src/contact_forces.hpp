// dem/src/contact_forces.hpp — the contact and wall forces of the DEM as a part that owns its
// state (as LAMMPS's Pair and its wall fix): the contact laws' coefficients, the packed bodies
// the force loop reads (pairs.hpp: Body) with their protocol flag, the chunk of touching pairs
// (pairs.hpp: PairChunk), and the tally of the last computation (its output). It works on the
// particles and the neighbour search its owner passes to each call (ForceInputs).
//
// The `packed` protocol: the rows of the bodies match the particles (same order and count) since
// the last force computation, i.e. no rebuild since (the owner calls unpack() when a rebuild
// starts); the step then keeps them current: the integration writes the owned bodies and resets
// the force and torque sums (gravity + fExt) after its half kick, and compute() with `stepped`
// packs only the ghosts' bodies.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "buffers.hpp"
#include "coloc/dem/dem.hpp"
#include "contact.hpp"
#include "neighbour_search.hpp"
#include "pairs.hpp"

namespace coloc::dem::detail {

/// What the last force computation saw: contacts of owned particles, wall contacts, the largest
/// overlap (fraction of the smaller radius) and its pair (partner -1: a wall).
struct ContactTally {
  long long contacts = 0, walls = 0;
  double maxOverlap = 0;
  std::int64_t maxOverlapId = -1, maxOverlapPartner = 0;
};

/// The contact laws (set once, setup.cpp): the model, rolling resistance of any material pair,
/// and the coefficients of every material pair and of every material against the walls.
struct ContactLaw {
  Model model = Model::HertzMindlin;
  bool rolling = false;
  int nMat = 0;
  std::vector<PairCoeff> pair;  // [a * nMat + b]
  std::vector<PairCoeff> wall;  // [a]
};

/// Which build of the force pass runs (particles.force_isa): the build's own target (pass 1
/// entry by entry), AVX-512 (pass 1 eight entries of a row at a time), or the widest the CPU
/// has. All give the same bits.
enum class ForceIsa { Widest, Scalar, Avx512 };

struct HeatPass;  // heat.hpp

/// What a force computation works on, lent by the owner for the call.
struct ForceInputs {
  ParticleStore& p;         // f and torque written (owned), the rest read
  NeighbourSearch& search;  // the list (slots taken and freed), the pool, the bins' box
  double dt;
  const double* g;  // gravity, 3
};

class ContactForces {
 public:
  ContactLaw law;

  /// Forces at the current state into f and torque of the owned particles: gravity + fExt +
  /// contacts + walls; `update`: the shear histories advance; `stepped`: inside the step, where
  /// the owned bodies and the reset sums are current when packed() (the integration's); `heat`
  /// (or nullptr): contact conduction in the same pass (force_pass.hpp).
  void compute(const ForceInputs& in, bool update, bool stepped, HeatPass* heat);
  /// The build of the force pass to run; false (and unchanged) when the CPU lacks it.
  bool selectIsa(ForceIsa want);
  ForceIsa isa() const { return isa_; }
  /// The bodies match the particles (see above).
  bool packed() const { return packed_; }
  /// The packed bodies (index = local particle), written by the integration when packed().
  Body* bodies() { return body_.data(); }
  /// The particles change order or count (a rebuild): the next compute() packs every body.
  void unpack() { packed_ = false; }
  /// The bodies' storage lent while unpacked (its contents are dead until the next compute()):
  /// at least `bytes`, grown if needed.
  unsigned char* lend(std::size_t bytes);
  const ContactTally& tally() const { return tally_; }
  std::size_t bodyBytes() const { return cap(body_); }

 private:
  /// The force and torque sums reset to gravity + fExt for the owned particles, and the bodies
  /// sized for every local particle.
  void resetSums(const ForceInputs& in);
  /// The bodies of particles [from, size) packed from the columns.
  void packBodies(const ParticleStore& p, std::size_t from);

  PairChunk chunk_;
  std::vector<Body> body_;
  bool packed_ = false;
  ForceIsa isa_ = ForceIsa::Scalar;
  ContactTally tally_;
};

}  // namespace coloc::dem::detail
