// What a failed write's system call said (no HDF5: also in the SMPI build). io_reason.hpp.
#include "io_reason.hpp"

#include <fmt/format.h>
#include <sys/statvfs.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace coloc::h5 {

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
  return fmt::format(" (No space left on device: {} bytes free on the file system of '{}')", avail,
                     dir.empty() ? std::string(".") : dir.string());
}

}  // namespace coloc::h5
