// Errors, handles, element types and the collective slab transfers of the io room
// (h5detail.hpp); the public calls are in h5file.cpp (the file, attributes) and datasets.cpp.
#include "h5detail.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>  // fmt::join
#include <sys/statvfs.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <vector>

namespace coloc::h5 {
namespace {

herr_t collectError(unsigned, const H5E_error2_t* e, void* data) {
  auto* out = static_cast<std::vector<std::string>*>(data);
  std::string s = e->func_name ? e->func_name : "";
  if (e->desc && *e->desc) s += std::string(s.empty() ? "" : ": ") + e->desc;
  out->push_back(std::move(s));
  return 0;
}

}  // namespace

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

Hid plist(hid_t cls, const char* what) {
  return Hid(checkId(H5Pcreate(cls), what), H5Pclose);
}

/// Link creation list that creates missing parent groups.
Hid parentsLcpl() {
  Hid l = plist(H5P_LINK_CREATE, "H5Pcreate(link)");
  checkErr(H5Pset_create_intermediate_group(l, 1), "H5Pset_create_intermediate_group");
  return l;
}

ElemTypes elemTypes(Elem e) {
  switch (e) {
    case Elem::I64:
      return {H5T_NATIVE_INT64, H5T_STD_I64LE, "integer"};
    case Elem::I32:
      return {H5T_NATIVE_INT32, H5T_STD_I32LE, "integer"};
    case Elem::F64:
      break;
  }
  return {H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, "float"};
}

namespace {

std::string dimsText(const hsize_t* d, int rank) {
  return fmt::format("[{}]", fmt::join(d, d + rank, ", "));
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

Hid collectiveXfer() {
  Hid x = plist(H5P_DATASET_XFER, "H5Pcreate(xfer)");
  checkErr(H5Pset_dxpl_mpio(x, H5FD_MPIO_COLLECTIVE), "H5Pset_dxpl_mpio");
  return x;
}

}  // namespace

std::string context(const H5File& f, const std::string& path) {
  return f.path() + ":" + path;
}

/// File access list: MPI-IO on `comm` (HDF5 keeps its own duplicate), collective metadata.
Hid mpioFapl(const FlatComm& comm, bool collectiveWrites) {
  Hid fapl = plist(H5P_FILE_ACCESS, "H5Pcreate(fapl)");
  checkErr(H5Pset_fapl_mpio(fapl, comm.get(), MPI_INFO_NULL), "H5Pset_fapl_mpio");
  checkErr(H5Pset_all_coll_metadata_ops(fapl, true), "H5Pset_all_coll_metadata_ops");
  if (collectiveWrites)
    checkErr(H5Pset_coll_metadata_write(fapl, true), "H5Pset_coll_metadata_write");
  return fapl;
}

/// Collective: create dataset `path` of shape s.global and write this rank's slab.
void writeSlab(H5File& file, const std::string& path, Elem e, const Slab& s, const void* buf,
               const std::string& localError) {
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
        for (int b = 0; b < s.rank; ++b)
          bytes *= static_cast<double>(chunk[static_cast<std::size_t>(b)]);
        if (bytes <= limit) break;
        auto& c = chunk[static_cast<std::size_t>(a)];
        c = std::max<hsize_t>(1, static_cast<hsize_t>(static_cast<double>(c) * limit / bytes));
      }
      checkErr(H5Pset_chunk(dcpl, s.rank, chunk.data()), "H5Pset_chunk");
      checkErr(H5Pset_fletcher32(dcpl), "H5Pset_fletcher32");
    }
    Hid lcpl = parentsLcpl();
    dset = Hid(checkId(H5Dcreate2(file.id(), path.c_str(), elemTypes(e).file, fspace, lcpl, dcpl,
                                  H5P_DEFAULT),
                       "H5Dcreate2"),
               H5Dclose);
    mspace = selectSlab(fspace, s);
    xfer = collectiveXfer();
  });
  // 3. the collective transfer (nothing to move when the global array is empty)
  if (s.globalElements() == 0) return;
  static const double dummy = 0;
  ioCollective(comm, ctx, [&] {
    checkErr(H5Dwrite(dset, elemTypes(e).mem, mspace, fspace, xfer, buf ? buf : &dummy),
             "H5Dwrite");
  });
}

/// Collective: read this rank's slab of dataset `path`, which must have shape s.global.
void readSlab(H5File& file, const std::string& path, Elem e, const Slab& s, void* buf,
              const std::string& localError) {
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
      throw LocalFailure(std::string("expected ") + elemTypes(e).name + " data");
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
    checkErr(H5Dread(dset, elemTypes(e).mem, mspace, fspace, xfer, buf ? buf : &dummy), "H5Dread");
  });
}
}  // namespace coloc::h5
