// io/src/h5detail.hpp — what the io room's HDF5 sources share (not a public header): errors made
// collective, owning handles, element types, and one rank's slab of a global dataset.
//
// Every HDF5 call that could fail on some ranks only runs inside collective()/ioCollective(): a
// failure on one rank becomes coloc::Error (or coloc::IoError for a write) on every rank, and no
// rank enters a collective HDF5 call that another skips.
#pragma once

#include <hdf5.h>
#include <mpi.h>

#include <array>
#include <cerrno>
#include <exception>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include "coloc/core/comm.hpp"
#include "coloc/core/error.hpp"
#include "coloc/io/h5io.hpp"
#include "io_reason.hpp"

namespace coloc::h5 {

// ---- errors -------------------------------------------------------------------------------------

/// A failure on this rank, turned into a collective coloc::Error by collective().
struct LocalFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// The HDF5 error stack as one line: the API call that failed and the innermost cause.
std::string h5ErrorText();
hid_t checkId(hid_t id, const char* what);
void checkErr(herr_t e, const char* what);
/// HDF5 prints its error stack to stderr by default; coloc reports errors itself.
void silenceHdf5();

/// Run `f` on every rank; a local failure becomes coloc::Error on every rank ("context: ..."),
/// coloc::IoError when `io` (a write: the driver exits with its I/O status).
template <class F>
void collective(const Comm& comm, const std::string& context, F&& f, bool io = false) {
  std::string err;
  errno = 0;
  try {
    f();
  } catch (const std::exception& e) {
    err = context + ": " + e.what();
    if (io) {
      std::string why = ioReason();
      if (why.empty()) why = spaceReason(context.substr(0, context.find(":/")));
      err += why;
    }
  }
  const std::string msg = comm.firstError(err, io ? 4 : 3);
  if (msg.empty()) return;
  if (io) throw IoError(msg);
  throw Error(msg);
}

/// collective() for a write: its failure is a coloc::IoError.
template <class F>
void ioCollective(const Comm& comm, const std::string& context, F&& f) {
  collective(comm, context, std::forward<F>(f), true);
}

// ---- handles ------------------------------------------------------------------------------------

class Hid {
 public:
  Hid() = default;
  Hid(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Hid(Hid&& o) noexcept : id_(std::exchange(o.id_, -1)), close_(o.close_) {}
  Hid& operator=(Hid&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, -1);
      close_ = o.close_;
    }
    return *this;
  }
  Hid(const Hid&) = delete;
  Hid& operator=(const Hid&) = delete;
  ~Hid() { reset(); }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
  }
  hid_t get() const { return id_; }
  operator hid_t() const { return id_; }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

Hid plist(hid_t cls, const char* what);
/// Link creation list that creates missing parent groups.
Hid parentsLcpl();

// ---- element types ------------------------------------------------------------------------------

enum class Elem { F64, I64, I32 };
template <class T>
constexpr Elem elemOf() {
  if constexpr (std::is_same_v<T, double>)
    return Elem::F64;
  else if constexpr (std::is_same_v<T, std::int64_t>)
    return Elem::I64;
  else {
    static_assert(std::is_same_v<T, int>, "double, int64 or int");
    return Elem::I32;
  }
}
/// The HDF5 types of an element kind: in memory (native), in the file (little-endian), and its
/// name in messages.
struct ElemTypes {
  hid_t mem, file;
  const char* name;
};
ElemTypes elemTypes(Elem e);

// ---- one rank's slab of a global array ----------------------------------------------------------

struct Slab {
  int rank = 1;
  std::array<hsize_t, 4> global{}, start{}, count{};
  hsize_t localElements() const {
    hsize_t n = 1;
    for (int a = 0; a < rank; ++a) n *= count[static_cast<std::size_t>(a)];
    return n;
  }
  hsize_t globalElements() const {
    hsize_t n = 1;
    for (int a = 0; a < rank; ++a) n *= global[static_cast<std::size_t>(a)];
    return n;
  }
};

/// "FILE:DATASET", the context of an error message.
std::string context(const H5File& f, const std::string& path);

/// The communicator handed to HDF5: the same ranks in the same order, without a Cartesian
/// topology. Open MPI's OMPIO (4.1.x, 5.0.x) groups its aggregators by the Cartesian topology and
/// then intermittently loses data of collective writes (open-mpi/ompi#12718; seen here at 4
/// ranks on a 2x2x1 grid); a plain communicator avoids that code path.
class FlatComm {
 public:
  explicit FlatComm(MPI_Comm c) {
    int topo = MPI_UNDEFINED;
    MPI_Topo_test(c, &topo);
    if (topo == MPI_UNDEFINED) {
      comm_ = c;
    } else {
      int rank = 0;
      MPI_Comm_rank(c, &rank);
      MPI_Comm_split(c, 0, rank, &comm_);
      owned_ = true;
    }
  }
  ~FlatComm() {
    if (owned_) MPI_Comm_free(&comm_);
  }
  FlatComm(const FlatComm&) = delete;
  FlatComm& operator=(const FlatComm&) = delete;
  MPI_Comm get() const { return comm_; }

 private:
  MPI_Comm comm_ = MPI_COMM_NULL;
  bool owned_ = false;
};

/// File access list: MPI-IO on `comm` (HDF5 keeps its own duplicate), collective metadata.
Hid mpioFapl(const FlatComm& comm, bool collectiveWrites);

/// Collective: create dataset `path` of shape s.global and write this rank's slab. `localError`
/// (non-empty on a rank whose data are unusable) fails every rank before any HDF5 call.
void writeSlab(H5File& file, const std::string& path, Elem e, const Slab& s, const void* buf,
               const std::string& localError = {});
/// Collective: read this rank's slab of dataset `path`, which must have shape s.global.
void readSlab(H5File& file, const std::string& path, Elem e, const Slab& s, void* buf,
              const std::string& localError = {});

}  // namespace coloc::h5
