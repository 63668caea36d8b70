// coloc/dem/fields.hpp — the per-particle field table: which SoA arrays of a ParticleStore travel
// in which operation (in the manner of LAMMPS' atom_vec fields_border / fields_comm /
// fields_exchange / fields_restart).
//
// Every per-particle array is one entry of forEachField below (the built-in members of
// ParticleStore) or one ParticleStore::addField call (extra quantities, double, registered at run
// time). The DEM packs and unpacks rows generically over this table for ghost build, ghost
// update, migration and its state (save/restore, re-balancing), and the checkpoint writer and
// reader iterate it: adding a per-particle quantity is one entry.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace coloc::dem {

/// The operations a field travels in (bit mask).
enum FieldOp : unsigned {
  kOpGhostBuild = 1u,   // copied to a ghost when the ghost plan is built (rebuilds)
  kOpGhostUpdate = 2u,  // refreshed on ghosts each step between rebuilds
  kOpMigrate = 4u,      // carried by a particle that changes rank
  kOpState = 8u,        // part of DemState: save/restore, re-balancing, checkpoint files
  kOpPosition = 16u,    // not an operation: the particle centre (periodic ghosts shift it)
};

/// One entry of the table: its name (the checkpoint dataset), components and operations.
struct FieldInfo {
  std::string_view name;
  int components = 1;
  unsigned ops = 0;
  bool extra = false;  // registered with ParticleStore::addField (not a built-in member)
};

/// A per-particle quantity registered at run time (ParticleStore::addField): `components`
/// columns of doubles.
struct ExtraField {
  std::string name;
  int components = 1;
  unsigned ops = 0;
  std::vector<std::vector<double>> data;  // [component][particle]
};

}  // namespace coloc::dem
