// The H5File (create through NAME.tmp, open, close and rename, discard on an error) and its
// attributes. Layout and rules: coloc/io/h5io.hpp.
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "coloc/core/error.hpp"
#include "coloc/core/failure.hpp"
#include "coloc/core/files.hpp"
#include "coloc/io/h5io.hpp"
#include "h5detail.hpp"

static_assert(std::is_same_v<hid_t, std::int64_t>, "H5File::id() assumes a 64-bit hid_t");

namespace coloc {
using namespace h5;
namespace {

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

}  // namespace

// ---- H5File -------------------------------------------------------------------------------------

namespace {

/// "" when `path` is a regular file that holds HDF5's signature where HDF5 looks for it (offset
/// 0, 512, 1024, 2048, ...); otherwise why not. `size` gets the file's size. Local: no MPI, no
/// HDF5 call.
std::string hdf5FileProblem(const std::string& path, long long& size) {
  if (const std::string why = notRegularFile(path); !why.empty()) return why;
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return std::string("cannot open: ") + std::strerror(errno);
  std::string problem = notRegularFile(fd);
  struct stat st {};
  if (problem.empty() && ::fstat(fd, &st) != 0) problem = std::strerror(errno);
  size = st.st_size;
  if (problem.empty() && st.st_size < 8)
    problem = st.st_size == 0 ? "cannot open: the file is empty (or the system reports no size "
                                "for it, as for /proc files): not an HDF5 file"
                              : "cannot open: too short for an HDF5 file";
  static const char kSignature[8] = {'\211', 'H', 'D', 'F', '\r', '\n', '\032', '\n'};
  bool found = false;
  for (long long at = 0; problem.empty() && !found && at + 8 <= st.st_size;
       at = at == 0 ? 512 : 2 * at) {
    char head[8];
    if (::pread(fd, head, 8, at) != 8) break;
    found = std::equal(head, head + 8, kSignature);
  }
  ::close(fd);
  if (problem.empty() && !found) problem = "cannot open: not an HDF5 file (no HDF5 signature)";
  return problem;
}

}  // namespace

bool hdf5Available() {
  return true;
}

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
  // Rank 0 checks the name and what is there (a regular file or nothing: never a link, a folder
  // or a device; coloc/core/files.hpp) and makes NAME.tmp afresh, so that HDF5 opens a new
  // regular file and no link; the verdict is shared before the collective create.
  ioCollective(comm, path, [&] {
    if (!comm.isRoot()) return;
    if (const std::string why = writeTargetProblem(path); !why.empty()) throw LocalFailure(why);
    try {
      ::close(createFresh(f.writePath_));
    } catch (const Error& e) {
      throw LocalFailure(e.what());
    }
  });
  const FlatComm flat(comm.raw());
  try {
    ioCollective(comm, path, [&] {
      Hid fapl = mpioFapl(flat, true);
      id = H5Fcreate(f.writePath_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
      if (id < 0) throw LocalFailure("cannot create '" + f.writePath_ + "': " + h5ErrorText());
    });
  } catch (const Error&) {
    if (comm.isRoot()) ::unlink(f.writePath_.c_str());  // the empty NAME.tmp made above
    throw;
  }
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
  // Every rank checks, without MPI, what it sees (a regular file: H5Fopen of a FIFO would wait
  // for a writer; HDF5's signature where HDF5 looks for it), and the ranks agree that they see
  // the same file (its size), all before the collective open: a file that is no HDF5 file, or
  // that reads differently on different ranks (/proc/self/...), would otherwise send the ranks
  // into different collectives inside HDF5's open, where no deadline reaches them.
  long long size = -1;
  collective(comm, path, [&] {
    const std::string problem = hdf5FileProblem(path, size);
    if (!problem.empty()) throw LocalFailure(problem);
  });
  const long long lo = comm.min(size), hi = comm.max(size);
  if (lo != hi)
    comm.raiseIfAny(comm.isRoot() ? fmt::format("{}: the ranks see files of different sizes "
                                                "({} and {} bytes): not one file",
                                                path, lo, hi)
                                  : std::string());
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
    if (failedSomewhere)
      std::filesystem::remove(writePath_, ec);
    else  // over a regular file only; a failed rename removes NAME.tmp (coloc/core/files.hpp)
      err = publishFile(writePath_, path_);
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

}  // namespace coloc
