// coloc/io/h5io.hpp — parallel HDF5 (MPI-IO driver, collective transfers) for fields and
// particles. The XDMF index that lets ParaView open a series of such files: coloc/io/xdmf.hpp.
//
// Every function here is COLLECTIVE over the communicator of the file: all its ranks call it,
// in the same order, with the same paths and names (the data differ). Failures (a file that
// cannot be created, a missing dataset, a shape mismatch, any HDF5 error) become coloc::Error on
// every rank, through Comm::raiseIfAny, never a hang or an HDF5 error dump.
//
// Layout on disk (x fastest, as in memory; docs/output.md):
//   cell field             double [nz][ny][nx]
//   cell vector            double [nz][ny][nx][3]   (components interleaved)
//   face component d       double [nz'][ny'][nx']   (one more face along d on a closed axis)
//   particle array         double | int64 | int32 [N]   (rank r's rows follow rank r-1's)
//   particle 3-vector      double [N][3]
//
// Files are created as NAME.tmp and renamed to NAME by close(): a run killed while writing leaves
// the previous NAME intact. A file destroyed without close() (an exception unwound it) is
// discarded. The file keeps a copy of the communicator handle: it must not outlive the
// Decomposition (or communicator) it was opened on.
#pragma once

#include <array>
#include <concepts>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "coloc/core/comm.hpp"
#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/field.hpp"

namespace coloc {

/// False in a build without HDF5 (the SimGrid SMPI build, -DCOLOC_SMPI=ON): every file function
/// below then throws coloc::Error saying so; callers refuse file keys before a run starts.
bool hdf5Available();

class H5File {
 public:
  /// Create (truncate) `path` for writing; the data go to `path`.tmp until close(). `sync`:
  /// flush to stable storage (MPI_File_sync) before the rename (checkpoints).
  static H5File create(const Comm& comm, const std::string& path, bool sync = false);
  /// Open an existing file read-only.
  static H5File openRead(const Comm& comm, const std::string& path);

  H5File() = default;
  H5File(H5File&& o) noexcept;
  H5File& operator=(H5File&& o) noexcept;
  H5File(const H5File&) = delete;
  H5File& operator=(const H5File&) = delete;
  /// Closes the handle; a created file that was not close()d is removed (NAME.tmp), NAME is left
  /// as it was.
  ~H5File();

  /// Close; for a created file, rename NAME.tmp to NAME (rank 0, after every rank closed).
  void close();
  bool isOpen() const { return id_ >= 0; }
  const Comm& comm() const { return comm_; }
  /// The final path (NAME, not NAME.tmp).
  const std::string& path() const { return path_; }
  bool writable() const { return writable_; }
  /// Datasets created from now on are chunked with HDF5's Fletcher32 checksum filter: a read of
  /// damaged data fails (checkpoints). Parallel filtered writes: collective, HDF5 >= 1.10.2.
  void setChecksums(bool on) { checksums_ = on; }
  bool checksums() const { return checksums_; }
  /// The HDF5 file id (hid_t), for code that needs HDF5 calls of its own.
  std::int64_t id() const { return id_; }

  /// Create a group and any missing parents ("a/b/c"); no error if it exists.
  void createGroup(const std::string& path);
  /// True if a group or dataset exists at `path` ("/" always does).
  bool exists(const std::string& path) const;
  /// Global shape of a dataset, slowest axis first.
  std::vector<long long> shape(const std::string& dataset) const;

  /// Attributes on a group or dataset ("/" for the file). An existing attribute is replaced.
  void setAttribute(const std::string& object, const std::string& name, double v);
  void setAttribute(const std::string& object, const std::string& name, const std::string& v);
  void setAttribute(const std::string& object, const std::string& name, const char* v) {
    setAttribute(object, name, std::string(v));
  }
  void setAttribute(const std::string& object, const std::string& name, std::span<const double> v);
  template <std::integral T>
  void setAttribute(const std::string& object, const std::string& name, T v) {
    setIntAttribute(object, name, static_cast<long long>(v));
  }
  double attributeDouble(const std::string& object, const std::string& name) const;
  long long attributeInt(const std::string& object, const std::string& name) const;
  std::string attributeString(const std::string& object, const std::string& name) const;
  std::vector<double> attributeDoubles(const std::string& object, const std::string& name) const;

 private:
  void setIntAttribute(const std::string& object, const std::string& name, long long v);
  void release() noexcept;
  Comm comm_;
  std::int64_t id_ = -1;
  std::string path_, writePath_;
  bool writable_ = false, sync_ = false, root_ = false, checksums_ = false;
  long long abortId_ = 0;  // writePath_ registered with removeOnAbort (core/failure.hpp)
};

// ---- fields: each rank writes/reads its owned block of the global array -----------------------

/// Owned cells of `f` -> global dataset [nz][ny][nx]. Intermediate groups are created.
void writeCellField(H5File& file, const std::string& path, const Decomposition& dec,
                    const CellField& f);
/// Global dataset [nz][ny][nx] -> owned cells of `f` (ghosts untouched). The file may have been
/// written by any decomposition of the same grid.
void readCellField(H5File& file, const std::string& path, const Decomposition& dec, CellField& f);
/// Three cell fields -> one dataset [nz][ny][nx][3] (what ParaView takes as a vector).
void writeCellVector(H5File& file, const std::string& path, const Decomposition& dec,
                     const CellField& x, const CellField& y, const CellField& z);
void readCellVector(H5File& file, const std::string& path, const Decomposition& dec, CellField& x,
                    CellField& y, CellField& z);
/// Face component d (layout faceLayout(dec, d, g)): the owned faces (faceOwned) -> global
/// dataset with N_d + 1 faces along d on a closed axis, N_d on a periodic one.
void writeFaceComponent(H5File& file, const std::string& path, const Decomposition& dec, int d,
                        const Field3<double>& f);
void readFaceComponent(H5File& file, const std::string& path, const Decomposition& dec, int d,
                       Field3<double>& f);

// ---- particles: rank r's rows follow those of ranks 0..r-1 ------------------------------------

/// Rows [offset, offset + count) of a global array of `total` rows.
struct RowRange {
  long long offset = 0, count = 0, total = 0;
};
/// The rows of `localCount` items per rank, ordered by rank (exclusive prefix sum). Collective.
RowRange rowsOf(const Comm& comm, long long localCount);
/// An even split of `total` rows over the ranks (restarts on any rank count). Local.
RowRange evenRows(const Comm& comm, long long total);

/// Structure-of-arrays 3-vector: three spans of equal length.
using Vec3Span = std::array<std::span<const double>, 3>;
/// The first n entries of each component (e.g. the owned particles of a ParticleStore).
Vec3Span firstRows(const std::array<std::vector<double>, 3>& soa, std::size_t n);

void writeParticleArray(H5File& file, const std::string& path, std::span<const double> local);
void writeParticleArray(H5File& file, const std::string& path, std::span<const std::int64_t> local);
void writeParticleArray(H5File& file, const std::string& path, std::span<const int> local);
/// Three components -> dataset [N][3].
void writeParticleVec3(H5File& file, const std::string& path, Vec3Span local);
/// Rows `rows` of a 1-D dataset (T = double, std::int64_t or int). Checks the dataset holds
/// rows.total rows.
template <class T>
std::vector<T> readParticleArray(H5File& file, const std::string& path, const RowRange& rows);
std::array<std::vector<double>, 3> readParticleVec3(H5File& file, const std::string& path,
                                                    const RowRange& rows);

}  // namespace coloc
