#include "coloc/partition/h5io.hpp"

#include <hdf5.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "coloc/core/error.hpp"
#include "coloc/core/failure.hpp"

static_assert(std::is_same_v<hid_t, std::int64_t>, "H5File::id() assumes a 64-bit hid_t");

namespace coloc {
namespace {

// ---- errors -------------------------------------------------------------------------------------

/// A failure on this rank, turned into a collective coloc::Error by collective().
struct LocalFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

herr_t collectError(unsigned, const H5E_error2_t* e, void* data) {
  auto* out = static_cast<std::vector<std::string>*>(data);
  std::string s = e->func_name ? e->func_name : "";
  if (e->desc && *e->desc) s += std::string(s.empty() ? "" : ": ") + e->desc;
  out->push_back(std::move(s));
  return 0;
}

/// The HDF5 error stack as one line: the API call that failed and the innermost cause.
std::string h5ErrorText() {
  std::vector<std::string> stack;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collectError, &stack);
  H5Eclear2(H5E_DEFAULT);
  if (stack.empty()) return "HDF5 error";
  std::string s = stack.front();
  if (stack.size() > 1) s += " (" + stack.back() + ")";
  return s;
}

hid_t checkId(hid_t id, const char* what) {
  if (id < 0) throw LocalFailure(std::string(what) + " failed: " + h5ErrorText());
  return id;
}
void checkErr(herr_t e, const char* what) {
  if (e < 0) throw LocalFailure(std::string(what) + " failed: " + h5ErrorText());
}

/// HDF5 prints its error stack to stderr by default; coloc reports errors itself.
void silenceHdf5() {
  static const bool done = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)done;
}

/// What the failed system call said, for the errors a user can act on (errno of the last call;
/// set to 0 before the HDF5 call by ioCollective).
std::string ioReason() {
  switch (errno) {
    case ENOSPC:
    case EDQUOT:
    case EFBIG:
    case EROFS:
    case EACCES:
    case EIO:
      return std::string(" (") + std::strerror(errno) + ")";
    default:
      return {};
  }
}

/// After a failed write whose errno says nothing (MPI-IO often keeps it): a nearly full file
/// system of `file` is named.
std::string spaceReason(const std::string& file) {
  struct statvfs st {};
  const std::filesystem::path dir = std::filesystem::path(file).parent_path();
  if (::statvfs(dir.empty() ? "." : dir.c_str(), &st) != 0) return {};
  const unsigned long long avail =
      static_cast<unsigned long long>(st.f_bavail) * static_cast<unsigned long long>(st.f_frsize);
  if (avail >= (1ull << 20)) return {};
  return " (No space left on device: " + std::to_string(avail) +
         " bytes free on the file system of '" + (dir.empty() ? std::string(".") : dir.string()) +
         "')";
}

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

Hid plist(hid_t cls, const char* what) {
  return Hid(checkId(H5Pcreate(cls), what), H5Pclose);
}

/// Link creation list that creates missing parent groups.
Hid parentsLcpl() {
  Hid l = plist(H5P_LINK_CREATE, "H5Pcreate(link)");
  checkErr(H5Pset_create_intermediate_group(l, 1), "H5Pset_create_intermediate_group");
  return l;
}

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
hid_t memType(Elem e) {
  switch (e) {
    case Elem::F64:
      return H5T_NATIVE_DOUBLE;
    case Elem::I64:
      return H5T_NATIVE_INT64;
    case Elem::I32:
      return H5T_NATIVE_INT32;
  }
  return H5T_NATIVE_DOUBLE;
}
hid_t fileType(Elem e) {
  switch (e) {
    case Elem::F64:
      return H5T_IEEE_F64LE;
    case Elem::I64:
      return H5T_STD_I64LE;
    case Elem::I32:
      return H5T_STD_I32LE;
  }
  return H5T_IEEE_F64LE;
}
const char* elemName(Elem e) {
  switch (e) {
    case Elem::F64:
      return "float";
    case Elem::I64:
    case Elem::I32:
      return "integer";
  }
  return "?";
}

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

std::string dimsText(const hsize_t* d, int rank) {
  std::string s = "[";
  for (int a = 0; a < rank; ++a) s += (a ? ", " : "") + std::to_string(d[a]);
  return s + "]";
}

std::string context(const H5File& f, const std::string& path) {
  return f.path() + ":" + path;
}

/// Select this rank's part of `fspace` and make the matching memory space.
Hid selectSlab(hid_t fspace, const Slab& s) {
  const hsize_t n = s.localElements();
  const hsize_t one = std::max<hsize_t>(n, 1);
  Hid mspace(checkId(H5Screate_simple(1, &one, nullptr), "H5Screate_simple"), H5Sclose);
  if (n == 0) {
    checkErr(H5Sselect_none(fspace), "H5Sselect_none");
    checkErr(H5Sselect_none(mspace), "H5Sselect_none");
  } else {
    checkErr(H5Sselect_hyperslab(fspace, H5S_SELECT_SET, s.start.data(), nullptr, s.count.data(),
                                 nullptr),
             "H5Sselect_hyperslab");
  }
  return mspace;
}

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
Hid mpioFapl(const FlatComm& comm, bool collectiveWrites) {
  Hid fapl = plist(H5P_FILE_ACCESS, "H5Pcreate(fapl)");
  checkErr(H5Pset_fapl_mpio(fapl, comm.get(), MPI_INFO_NULL), "H5Pset_fapl_mpio");
  checkErr(H5Pset_all_coll_metadata_ops(fapl, 1), "H5Pset_all_coll_metadata_ops");
  if (collectiveWrites) checkErr(H5Pset_coll_metadata_write(fapl, 1), "H5Pset_coll_metadata_write");
  return fapl;
}

Hid collectiveXfer() {
  Hid x = plist(H5P_DATASET_XFER, "H5Pcreate(xfer)");
  checkErr(H5Pset_dxpl_mpio(x, H5FD_MPIO_COLLECTIVE), "H5Pset_dxpl_mpio");
  return x;
}

/// Collective: create dataset `path` of shape s.global and write this rank's slab.
void writeSlab(H5File& file, const std::string& path, Elem e, const Slab& s, const void* buf,
               const std::string& localError = {}) {
  const Comm& comm = file.comm();
  const std::string ctx = context(file, path);
  // 1. local checks, so that no rank enters a collective HDF5 call another rank skips
  collective(comm, ctx, [&] {
    if (!localError.empty()) throw LocalFailure(localError);
    if (!file.isOpen()) throw LocalFailure("file is not open");
    if (!file.writable()) throw LocalFailure("file is open read-only");
    if (path.empty() || path.back() == '/') throw LocalFailure("bad dataset path");
  });
  // 2. dataset creation (the same metadata operation on every rank) and selection
  Hid fspace, mspace, dset, xfer;
  ioCollective(comm, ctx, [&] {
    fspace = Hid(checkId(H5Screate_simple(s.rank, s.global.data(), nullptr), "H5Screate_simple"),
                 H5Sclose);
    Hid dcpl = plist(H5P_DATASET_CREATE, "H5Pcreate(dcpl)");
    checkErr(H5Pset_fill_time(dcpl, H5D_FILL_TIME_NEVER), "H5Pset_fill_time");
    if (file.checksums() && s.globalElements() > 0) {
      // Chunks of at most 4 MiB (slowest axes cut first), each with its Fletcher32 checksum.
      std::array<hsize_t, 4> chunk = s.global;
      const double limit = 4.0 * 1024 * 1024;
      for (int a = 0; a < s.rank; ++a) {
        double bytes = 8;
        for (int b = 0; b < s.rank; ++b) bytes *= static_cast<double>(chunk[static_cast<std::size_t>(b)]);
        if (bytes <= limit) break;
        auto& c = chunk[static_cast<std::size_t>(a)];
        c = std::max<hsize_t>(1, static_cast<hsize_t>(static_cast<double>(c) * limit / bytes));
      }
      checkErr(H5Pset_chunk(dcpl, s.rank, chunk.data()), "H5Pset_chunk");
      checkErr(H5Pset_fletcher32(dcpl), "H5Pset_fletcher32");
    }
    Hid lcpl = parentsLcpl();
    dset = Hid(
        checkId(H5Dcreate2(file.id(), path.c_str(), fileType(e), fspace, lcpl, dcpl, H5P_DEFAULT),
                "H5Dcreate2"),
        H5Dclose);
    mspace = selectSlab(fspace, s);
    xfer = collectiveXfer();
  });
  // 3. the collective transfer (nothing to move when the global array is empty)
  if (s.globalElements() == 0) return;
  static const double dummy = 0;
  ioCollective(comm, ctx, [&] {
    checkErr(H5Dwrite(dset, memType(e), mspace, fspace, xfer, buf ? buf : &dummy), "H5Dwrite");
  });
}

/// Collective: read this rank's slab of dataset `path`, which must have shape s.global.
void readSlab(H5File& file, const std::string& path, Elem e, const Slab& s, void* buf,
              const std::string& localError = {}) {
  const Comm& comm = file.comm();
  const std::string ctx = context(file, path);
  collective(comm, ctx, [&] {
    if (!localError.empty()) throw LocalFailure(localError);
    if (!file.isOpen()) throw LocalFailure("file is not open");
  });
  Hid fspace, mspace, dset, xfer;
  collective(comm, ctx, [&] {
    if (!file.exists(path)) throw LocalFailure("no such dataset");
    dset = Hid(checkId(H5Dopen2(file.id(), path.c_str(), H5P_DEFAULT), "H5Dopen2"), H5Dclose);
    Hid type(checkId(H5Dget_type(dset), "H5Dget_type"), H5Tclose);
    const H5T_class_t cls = H5Tget_class(type);
    const bool wantFloat = e == Elem::F64;
    if ((wantFloat && cls != H5T_FLOAT) || (!wantFloat && cls != H5T_INTEGER))
      throw LocalFailure(std::string("expected ") + elemName(e) + " data");
    fspace = Hid(checkId(H5Dget_space(dset), "H5Dget_space"), H5Sclose);
    const int rank = H5Sget_simple_extent_ndims(fspace);
    std::array<hsize_t, 8> dims{};
    if (rank < 0 || rank > 8) throw LocalFailure("unsupported dataspace");
    H5Sget_simple_extent_dims(fspace, dims.data(), nullptr);
    bool same = rank == s.rank;
    for (int a = 0; same && a < rank; ++a)
      same = dims[static_cast<std::size_t>(a)] == s.global[static_cast<std::size_t>(a)];
    if (!same)
      throw LocalFailure("shape " + dimsText(dims.data(), rank) + ", expected " +
                         dimsText(s.global.data(), s.rank));
    mspace = selectSlab(fspace, s);
    xfer = collectiveXfer();
  });
  if (s.globalElements() == 0) return;
  static double dummy = 0;
  collective(comm, ctx, [&] {
    checkErr(H5Dread(dset, memType(e), mspace, fspace, xfer, buf ? buf : &dummy), "H5Dread");
  });
}

// ---- fields -------------------------------------------------------------------------------------

/// The slab of an owned box `owned` (local indices) of a global array of `globalN` entries per
/// axis, with `comps` interleaved components ([z][y][x] or [z][y][x][comps]).
Slab fieldSlab(const Decomposition& dec, const IndexBox& owned, Int3 globalN, int comps) {
  Slab s;
  s.rank = comps > 1 ? 4 : 3;
  for (int a = 0; a < 3; ++a) {
    const int d = 2 - a;  // z, y, x
    const auto i = static_cast<std::size_t>(a);
    s.global[i] = static_cast<hsize_t>(globalN[d]);
    s.start[i] = static_cast<hsize_t>(dec.lo()[d] + owned.lo[d]);
    s.count[i] = static_cast<hsize_t>(std::max(0, owned.hi[d] - owned.lo[d]));
  }
  s.global[3] = s.count[3] = static_cast<hsize_t>(comps);
  return s;
}

std::string layoutError(const Decomposition& dec, const Field3<double>& f, Int3 stagger) {
  const auto& l = f.layout();
  if (l.n != dec.cells() || l.stagger != stagger)
    return "field layout does not match this rank's block (owned cells " + std::to_string(l.n[0]) +
           "x" + std::to_string(l.n[1]) + "x" + std::to_string(l.n[2]) + ", block " +
           std::to_string(dec.cells()[0]) + "x" + std::to_string(dec.cells()[1]) + "x" +
           std::to_string(dec.cells()[2]) + ")";
  return {};
}

/// Copy the owned box of the fields into buf (x fastest, components interleaved), and back.
void packBox(std::span<const Field3<double>* const> fields, const IndexBox& b,
             std::vector<double>& buf) {
  std::size_t at = 0;
  forEach(b, [&](int i, int j, int k) {
    for (const auto* f : fields) buf[at++] = (*f)(i, j, k);
  });
}
void unpackBox(std::span<Field3<double>* const> fields, const IndexBox& b,
               const std::vector<double>& buf) {
  std::size_t at = 0;
  forEach(b, [&](int i, int j, int k) {
    for (auto* f : fields) (*f)(i, j, k) = buf[at++];
  });
}

void writeBox(H5File& file, const std::string& path, const Decomposition& dec,
              std::span<const Field3<double>* const> fields, const IndexBox& owned, Int3 globalN,
              Int3 stagger) {
  std::string err;
  for (const auto* f : fields)
    if (err.empty()) err = layoutError(dec, *f, stagger);
  const Slab s = fieldSlab(dec, owned, globalN, static_cast<int>(fields.size()));
  std::vector<double> buf;
  if (err.empty()) {
    buf.resize(static_cast<std::size_t>(s.localElements()));
    packBox(fields, owned, buf);
  }
  writeSlab(file, path, Elem::F64, s, buf.data(), err);
}

void readBox(H5File& file, const std::string& path, const Decomposition& dec,
             std::span<Field3<double>* const> fields, const IndexBox& owned, Int3 globalN,
             Int3 stagger) {
  std::string err;
  for (const auto* f : fields)
    if (err.empty()) err = layoutError(dec, *f, stagger);
  const Slab s = fieldSlab(dec, owned, globalN, static_cast<int>(fields.size()));
  std::vector<double> buf(err.empty() ? static_cast<std::size_t>(s.localElements()) : 0);
  readSlab(file, path, Elem::F64, s, buf.data(), err);
  unpackBox(fields, owned, buf);
}

Int3 faceGlobal(const Decomposition& dec, int d) {
  Int3 n = dec.grid().cells;
  if (!dec.grid().periodic[d]) n[d] += 1;
  return n;
}
Int3 staggerOf(int d) {
  Int3 s{0, 0, 0};
  s[d] = 1;
  return s;
}

// ---- particles ----------------------------------------------------------------------------------

Slab rowSlab(const RowRange& r, int comps) {
  Slab s;
  s.rank = comps > 1 ? 2 : 1;
  s.global = {static_cast<hsize_t>(r.total), static_cast<hsize_t>(comps), 0, 0};
  s.start = {static_cast<hsize_t>(r.offset), 0, 0, 0};
  s.count = {static_cast<hsize_t>(r.count), static_cast<hsize_t>(comps), 0, 0};
  return s;
}

template <class T>
void writeRows(H5File& file, const std::string& path, std::span<const T> local) {
  const RowRange r = rowsOf(file.comm(), static_cast<long long>(local.size()));
  writeSlab(file, path, elemOf<T>(), rowSlab(r, 1), local.data());
}

// ---- attributes ---------------------------------------------------------------------------------

void writeAttribute(H5File& file, const std::string& object, const std::string& name, hid_t ftype,
                    hid_t mtype, hsize_t n, bool scalar, const void* data) {
  ioCollective(file.comm(), context(file, object) + " attribute '" + name + "'", [&] {
    if (!file.writable()) throw LocalFailure("file is open read-only");
    if (!file.exists(object)) throw LocalFailure("no such object");
    Hid obj(checkId(H5Oopen(file.id(), object.c_str(), H5P_DEFAULT), "H5Oopen"), H5Oclose);
    const htri_t has = H5Aexists(obj, name.c_str());
    checkErr(has < 0 ? -1 : 0, "H5Aexists");
    if (has > 0) checkErr(H5Adelete(obj, name.c_str()), "H5Adelete");
    Hid space(
        checkId(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr), "H5Screate"),
        H5Sclose);
    Hid attr(checkId(H5Acreate2(obj, name.c_str(), ftype, space, H5P_DEFAULT, H5P_DEFAULT),
                     "H5Acreate2"),
             H5Aclose);
    checkErr(H5Awrite(attr, mtype, data), "H5Awrite");
  });
}

/// Open an attribute and call f(attr, type, space) collectively.
template <class F>
void readAttribute(const H5File& file, const std::string& object, const std::string& name, F&& f) {
  collective(file.comm(), context(file, object) + " attribute '" + name + "'", [&] {
    if (!file.isOpen()) throw LocalFailure("file is not open");
    if (!file.exists(object)) throw LocalFailure("no such object");
    Hid obj(checkId(H5Oopen(file.id(), object.c_str(), H5P_DEFAULT), "H5Oopen"), H5Oclose);
    const htri_t has = H5Aexists(obj, name.c_str());
    if (has <= 0) throw LocalFailure("no such attribute");
    Hid attr(checkId(H5Aopen(obj, name.c_str(), H5P_DEFAULT), "H5Aopen"), H5Aclose);
    Hid type(checkId(H5Aget_type(attr), "H5Aget_type"), H5Tclose);
    Hid space(checkId(H5Aget_space(attr), "H5Aget_space"), H5Sclose);
    f(attr, type, space);
  });
}

hsize_t attributeLength(hid_t space) {
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  if (n < 0) throw LocalFailure("H5Sget_simple_extent_npoints failed");
  return static_cast<hsize_t>(n);
}

// ---- XDMF ---------------------------------------------------------------------------------------

std::string xmlEscape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      case '\'':
        o += "&apos;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

// Shortest text that reads back as exactly v (0.005, not 0.0050000000000000001).
std::string num(double v) {
  char b[32];
  const auto r = std::to_chars(b, b + sizeof b, v);
  return std::string(b, r.ptr);
}

}  // namespace

// ---- H5File -------------------------------------------------------------------------------------

H5File H5File::create(const Comm& comm, const std::string& path, bool sync) {
  silenceHdf5();
  H5File f;
  f.comm_ = comm;
  f.path_ = path;
  f.writePath_ = path + ".tmp";
  f.writable_ = true;
  f.sync_ = sync;
  f.root_ = comm.isRoot();
  f.abortId_ = removeOnAbort(f.writePath_);  // a deadline stop leaves no partial file
  hid_t id = -1;
  const FlatComm flat(comm.raw());
  ioCollective(comm, path, [&] {
    Hid fapl = mpioFapl(flat, true);
    id = H5Fcreate(f.writePath_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    if (id < 0) throw LocalFailure("cannot create '" + f.writePath_ + "': " + h5ErrorText());
  });
  f.id_ = id;
  return f;
}

H5File H5File::openRead(const Comm& comm, const std::string& path) {
  silenceHdf5();
  H5File f;
  f.comm_ = comm;
  f.path_ = f.writePath_ = path;
  f.root_ = comm.isRoot();
  hid_t id = -1;
  collective(comm, path, [&] {
    if (!std::filesystem::exists(path)) throw LocalFailure("no such file");
  });
  const FlatComm flat(comm.raw());
  collective(comm, path, [&] {
    Hid fapl = mpioFapl(flat, false);
    id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl);
    if (id < 0) throw LocalFailure("cannot open: " + h5ErrorText());
  });
  f.id_ = id;
  return f;
}

H5File::H5File(H5File&& o) noexcept
    : comm_(o.comm_),
      id_(std::exchange(o.id_, -1)),
      path_(std::move(o.path_)),
      writePath_(std::move(o.writePath_)),
      writable_(o.writable_),
      sync_(o.sync_),
      root_(o.root_),
      checksums_(o.checksums_),
      abortId_(std::exchange(o.abortId_, 0)) {}

H5File& H5File::operator=(H5File&& o) noexcept {
  if (this != &o) {
    release();
    comm_ = o.comm_;
    id_ = std::exchange(o.id_, -1);
    path_ = std::move(o.path_);
    writePath_ = std::move(o.writePath_);
    writable_ = o.writable_;
    sync_ = o.sync_;
    root_ = o.root_;
    checksums_ = o.checksums_;
    abortId_ = std::exchange(o.abortId_, 0);
  }
  return *this;
}

H5File::~H5File() {
  release();
}

void H5File::release() noexcept {
  if (id_ < 0) {
    forgetOnAbort(std::exchange(abortId_, 0));
    return;
  }
  {
    // An error path (the file is discarded): H5Fclose is collective and may not return if a
    // rank fails inside it (a full disk while flushing the metadata): end every rank rather
    // than hang (coloc/core/failure.hpp).
    const FailureDeadline deadline("closing '" + writePath_ + "' after the error did not complete",
                                   writable_ ? 4 : 3);
    // The file is discarded: empty it first, so that the metadata HDF5 flushes while closing
    // finds room on a full disk (a rank failing there would leave the others in a barrier).
    if (writable_ && root_) {
      std::error_code ec;
      std::filesystem::resize_file(writePath_, 0, ec);
    }
    H5Fclose(static_cast<hid_t>(id_));
  }
  id_ = -1;
  if (writable_ && root_) {  // no MPI call here: the communicator may be gone
    std::error_code ec;
    std::filesystem::remove(writePath_, ec);
  }
  forgetOnAbort(std::exchange(abortId_, 0));
}

void H5File::close() {
  if (id_ < 0) return;
  std::string err;
  errno = 0;
  if (writable_ && sync_ && H5Fflush(static_cast<hid_t>(id_), H5F_SCOPE_GLOBAL) < 0)
    err = "H5Fflush failed: " + h5ErrorText() + ioReason();
  if (!err.empty()) noteLocalFailure(writePath_ + ": " + err, 4);  // H5Fclose is collective
  if (H5Fclose(static_cast<hid_t>(id_)) < 0 && err.empty())
    err = "H5Fclose failed: " + h5ErrorText() + ioReason();
  id_ = -1;
  if (!err.empty()) err = writePath_ + ": " + err;
  if (!err.empty()) noteLocalFailure(err, 4);
  // Every rank has closed once the reduction returns; rank 0 then publishes the file under its
  // name, or removes it when some rank failed.
  const bool failedSomewhere = comm_.max(err.empty() ? 0 : 1) != 0;
  if (failedSomewhere) failureShared();
  if (writable_ && comm_.isRoot()) {
    std::error_code ec;
    if (failedSomewhere) {
      std::filesystem::remove(writePath_, ec);
    } else {
      std::filesystem::rename(writePath_, path_, ec);
      if (ec) err = "cannot rename '" + writePath_ + "' to '" + path_ + "': " + ec.message();
    }
  }
  forgetOnAbort(std::exchange(abortId_, 0));
  if (const std::string msg = comm_.firstError(err, 4); !msg.empty()) throw IoError(msg);
}

void H5File::createGroup(const std::string& path) {
  collective(comm_, context(*this, path), [&] {
    if (!writable_) throw LocalFailure("file is open read-only");
  });
  ioCollective(comm_, context(*this, path), [&] {
    if (exists(path)) return;
    Hid lcpl = parentsLcpl();
    Hid g(checkId(H5Gcreate2(id_, path.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT), "H5Gcreate2"),
          H5Gclose);
  });
}

bool H5File::exists(const std::string& path) const {
  if (id_ < 0) return false;
  // H5Lexists fails on a missing parent: check every prefix.
  std::string prefix;
  std::size_t pos = 0;
  while (pos < path.size()) {
    std::size_t next = path.find('/', pos);
    if (next == std::string::npos) next = path.size();
    if (next > pos) {
      if (!prefix.empty() || path[0] == '/') prefix.push_back('/');
      prefix.append(path, pos, next - pos);
      if (H5Lexists(static_cast<hid_t>(id_), prefix.c_str(), H5P_DEFAULT) <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return false;
      }
    }
    pos = next + 1;
  }
  return true;
}

std::vector<long long> H5File::shape(const std::string& dataset) const {
  std::vector<long long> out;
  collective(comm_, context(*this, dataset), [&] {
    if (!exists(dataset)) throw LocalFailure("no such dataset");
    Hid d(checkId(H5Dopen2(id_, dataset.c_str(), H5P_DEFAULT), "H5Dopen2"), H5Dclose);
    Hid s(checkId(H5Dget_space(d), "H5Dget_space"), H5Sclose);
    const int rank = H5Sget_simple_extent_ndims(s);
    if (rank < 0) throw LocalFailure("H5Sget_simple_extent_ndims failed");
    std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
    H5Sget_simple_extent_dims(s, dims.data(), nullptr);
    out.assign(dims.begin(), dims.end());
  });
  return out;
}

void H5File::setAttribute(const std::string& object, const std::string& name, double v) {
  writeAttribute(*this, object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, true, &v);
}

void H5File::setIntAttribute(const std::string& object, const std::string& name, long long v) {
  const std::int64_t x = v;
  writeAttribute(*this, object, name, H5T_STD_I64LE, H5T_NATIVE_INT64, 1, true, &x);
}

void H5File::setAttribute(const std::string& object, const std::string& name,
                          std::span<const double> v) {
  static const double dummy = 0;
  writeAttribute(*this, object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v.size(), false,
                 v.empty() ? &dummy : v.data());
}

void H5File::setAttribute(const std::string& object, const std::string& name,
                          const std::string& v) {
  // Fixed-length, NUL-padded string (h5py reads it as bytes).
  std::string err;
  hid_t t = H5Tcopy(H5T_C_S1);
  if (t < 0 || H5Tset_size(t, std::max<std::size_t>(v.size(), 1)) < 0 ||
      H5Tset_strpad(t, H5T_STR_NULLPAD) < 0)
    err = "cannot make a string type: " + h5ErrorText();
  Hid type(t, H5Tclose);
  comm_.raiseIfAny(err);
  const std::string data = v.empty() ? std::string(1, '\0') : v;
  writeAttribute(*this, object, name, type, type, 1, true, data.data());
}

double H5File::attributeDouble(const std::string& object, const std::string& name) const {
  double v = 0;
  readAttribute(*this, object, name, [&](hid_t a, hid_t type, hid_t space) {
    if (H5Tget_class(type) != H5T_FLOAT && H5Tget_class(type) != H5T_INTEGER)
      throw LocalFailure("not a number");
    if (attributeLength(space) != 1) throw LocalFailure("not a scalar");
    checkErr(H5Aread(a, H5T_NATIVE_DOUBLE, &v), "H5Aread");
  });
  return v;
}

long long H5File::attributeInt(const std::string& object, const std::string& name) const {
  std::int64_t v = 0;
  readAttribute(*this, object, name, [&](hid_t a, hid_t type, hid_t space) {
    if (H5Tget_class(type) != H5T_INTEGER) throw LocalFailure("not an integer");
    if (attributeLength(space) != 1) throw LocalFailure("not a scalar");
    checkErr(H5Aread(a, H5T_NATIVE_INT64, &v), "H5Aread");
  });
  return v;
}

std::vector<double> H5File::attributeDoubles(const std::string& object,
                                             const std::string& name) const {
  std::vector<double> v;
  readAttribute(*this, object, name, [&](hid_t a, hid_t type, hid_t space) {
    if (H5Tget_class(type) != H5T_FLOAT && H5Tget_class(type) != H5T_INTEGER)
      throw LocalFailure("not a number");
    v.resize(attributeLength(space));
    if (!v.empty()) checkErr(H5Aread(a, H5T_NATIVE_DOUBLE, v.data()), "H5Aread");
  });
  return v;
}

std::string H5File::attributeString(const std::string& object, const std::string& name) const {
  std::string v;
  readAttribute(*this, object, name, [&](hid_t a, hid_t type, hid_t) {
    if (H5Tget_class(type) != H5T_STRING) throw LocalFailure("not a string");
    if (H5Tis_variable_str(type) > 0) throw LocalFailure("variable-length strings not supported");
    const std::size_t n = H5Tget_size(type);
    std::string buf(n, '\0');
    checkErr(H5Aread(a, type, buf.data()), "H5Aread");
    v = buf.substr(0, buf.find('\0'));
  });
  return v;
}

// ---- fields -------------------------------------------------------------------------------------

void writeCellField(H5File& file, const std::string& path, const Decomposition& dec,
                    const CellField& f) {
  const Field3<double>* p[1] = {&f};
  writeBox(file, path, dec, p, IndexBox{{0, 0, 0}, dec.cells()}, dec.grid().cells, {0, 0, 0});
}

void readCellField(H5File& file, const std::string& path, const Decomposition& dec, CellField& f) {
  Field3<double>* p[1] = {&f};
  readBox(file, path, dec, p, IndexBox{{0, 0, 0}, dec.cells()}, dec.grid().cells, {0, 0, 0});
}

void writeCellVector(H5File& file, const std::string& path, const Decomposition& dec,
                     const CellField& x, const CellField& y, const CellField& z) {
  const Field3<double>* p[3] = {&x, &y, &z};
  writeBox(file, path, dec, p, IndexBox{{0, 0, 0}, dec.cells()}, dec.grid().cells, {0, 0, 0});
}

void readCellVector(H5File& file, const std::string& path, const Decomposition& dec, CellField& x,
                    CellField& y, CellField& z) {
  Field3<double>* p[3] = {&x, &y, &z};
  readBox(file, path, dec, p, IndexBox{{0, 0, 0}, dec.cells()}, dec.grid().cells, {0, 0, 0});
}

void writeFaceComponent(H5File& file, const std::string& path, const Decomposition& dec, int d,
                        const Field3<double>& f) {
  const Field3<double>* p[1] = {&f};
  writeBox(file, path, dec, p, faceOwned(dec, d), faceGlobal(dec, d), staggerOf(d));
}

void readFaceComponent(H5File& file, const std::string& path, const Decomposition& dec, int d,
                       Field3<double>& f) {
  Field3<double>* p[1] = {&f};
  readBox(file, path, dec, p, faceOwned(dec, d), faceGlobal(dec, d), staggerOf(d));
}

// ---- particles ----------------------------------------------------------------------------------

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

void writeParticleArray(H5File& file, const std::string& path, std::span<const double> local) {
  writeRows(file, path, local);
}
void writeParticleArray(H5File& file, const std::string& path,
                        std::span<const std::int64_t> local) {
  writeRows(file, path, local);
}
void writeParticleArray(H5File& file, const std::string& path, std::span<const int> local) {
  writeRows(file, path, local);
}

void writeParticleVec3(H5File& file, const std::string& path, Vec3Span local) {
  std::string err;
  const std::size_t n = local[0].size();
  if (local[1].size() != n || local[2].size() != n)
    err = "the three components have different lengths";
  const RowRange r = rowsOf(file.comm(), err.empty() ? static_cast<long long>(n) : 0);
  std::vector<double> buf;
  if (err.empty()) {
    buf.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t c = 0; c < 3; ++c) buf[3 * i + c] = local[c][i];
  }
  writeSlab(file, path, Elem::F64, rowSlab(r, 3), buf.data(), err);
}

template <class T>
std::vector<T> readParticleArray(H5File& file, const std::string& path, const RowRange& rows) {
  std::vector<T> out(static_cast<std::size_t>(std::max(0LL, rows.count)));
  readSlab(file, path, elemOf<T>(), rowSlab(rows, 1), out.data());
  return out;
}
template std::vector<double> readParticleArray<double>(H5File&, const std::string&,
                                                       const RowRange&);
template std::vector<std::int64_t> readParticleArray<std::int64_t>(H5File&, const std::string&,
                                                                   const RowRange&);
template std::vector<int> readParticleArray<int>(H5File&, const std::string&, const RowRange&);

std::array<std::vector<double>, 3> readParticleVec3(H5File& file, const std::string& path,
                                                    const RowRange& rows) {
  const auto n = static_cast<std::size_t>(std::max(0LL, rows.count));
  std::vector<double> buf(3 * n);
  readSlab(file, path, Elem::F64, rowSlab(rows, 3), buf.data());
  std::array<std::vector<double>, 3> out;
  for (std::size_t c = 0; c < 3; ++c) {
    out[c].resize(n);
    for (std::size_t i = 0; i < n; ++i) out[c][i] = buf[3 * i + c];
  }
  return out;
}

// ---- XDMF ---------------------------------------------------------------------------------------

XdmfSeries XdmfSeries::cells(std::string name, const GlobalGrid& grid) {
  XdmfSeries s;
  s.name_ = std::move(name);
  s.grid_ = grid;
  return s;
}

XdmfSeries XdmfSeries::particles(std::string name) {
  XdmfSeries s;
  s.name_ = std::move(name);
  s.particles_ = true;
  return s;
}

void XdmfSeries::add(XdmfStep s) {
  std::erase_if(steps_, [&](const XdmfStep& o) { return o.step >= s.step; });
  steps_.push_back(std::move(s));
}

std::string XdmfSeries::xml() const {
  std::ostringstream o;
  const auto& g = grid_;
  const std::string cellDims = std::to_string(g.cells[2]) + " " + std::to_string(g.cells[1]) + " " +
                               std::to_string(g.cells[0]);
  o << "<?xml version=\"1.0\" ?>\n"
    << "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    << "<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n"
    << " <Domain>\n"
    << "  <Grid Name=\"" << xmlEscape(name_)
    << "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const auto& s : steps_) {
    const std::string n = std::to_string(s.count);
    auto dataItem = [&](const std::string& dims, const std::string& type, int precision,
                        const std::string& dataset) {
      o << "     <DataItem Dimensions=\"" << dims << "\" NumberType=\"" << type << "\" Precision=\""
        << precision << "\" Format=\"HDF\">" << xmlEscape(s.file) << ":" << xmlEscape(dataset)
        << "</DataItem>\n";
    };
    o << "   <Grid Name=\"" << xmlEscape(name_) << "_" << s.step << "\" GridType=\"Uniform\">\n"
      << "    <Time Value=\"" << num(s.time) << "\"/>\n";
    if (particles_) {
      // N one-point cells. The explicit connectivity matters: without it the Xdmf3 readers
      // (ParaView's default) make the N points but no cells, and Surface shows nothing.
      o << "    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n
        << "\" NodesPerElement=\"1\">\n";
      dataItem(n + " 1", "Int", 8, s.connectivity);
      o << "    </Topology>\n"
        << "    <Geometry GeometryType=\"XYZ\">\n";
      dataItem(n + " 3", "Float", 8, s.geometry);
      o << "    </Geometry>\n";
    } else {
      o << "    <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << g.cells[2] + 1 << " "
        << g.cells[1] + 1 << " " << g.cells[0] + 1 << "\"/>\n"
        << "    <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
        << "     <DataItem Name=\"Origin\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" "
           "Format=\"XML\">"
        << num(g.origin[2]) << " " << num(g.origin[1]) << " " << num(g.origin[0]) << "</DataItem>\n"
        << "     <DataItem Name=\"Spacing\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" "
           "Format=\"XML\">"
        << num(g.spacing(2)) << " " << num(g.spacing(1)) << " " << num(g.spacing(0))
        << "</DataItem>\n"
        << "    </Geometry>\n";
    }
    for (const auto& a : s.attributes) {
      const std::string base = particles_ ? n : cellDims;
      o << "    <Attribute Name=\"" << xmlEscape(a.name) << "\" AttributeType=\""
        << (a.vector ? "Vector" : "Scalar") << "\" Center=\"" << (particles_ ? "Node" : "Cell")
        << "\">\n";
      dataItem(a.vector ? base + " 3" : base, a.numberType, a.precision, a.dataset);
      o << "    </Attribute>\n";
    }
    o << "   </Grid>\n";
  }
  o << "  </Grid>\n </Domain>\n</Xdmf>\n";
  return o.str();
}

void XdmfSeries::write(const Comm& comm, const std::string& path) const {
  std::string err;
  if (comm.isRoot()) {
    const std::string tmp = path + ".tmp";
    {
      std::ofstream out(tmp, std::ios::trunc);
      errno = 0;
      out << xml();
      out.flush();
      if (!out) err = "cannot write '" + tmp + "'" + ioReason();
    }
    std::error_code ec;
    if (err.empty()) {
      std::filesystem::rename(tmp, path, ec);
      if (ec) err = "cannot rename '" + tmp + "' to '" + path + "': " + ec.message();
    }
    if (!err.empty()) std::filesystem::remove(tmp, ec);
  }
  if (const std::string msg = comm.firstError(err, 4); !msg.empty()) throw IoError(msg);
}

}  // namespace coloc
