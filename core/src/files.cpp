// What a file given for reading must be (coloc/core/files.hpp).
#include "coloc/core/files.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

namespace coloc {
namespace {

std::string kindProblem(mode_t mode) {
  if (S_ISREG(mode)) return "";
  if (S_ISDIR(mode)) return "is a directory, not a file";
  if (S_ISFIFO(mode)) return "is a FIFO (named pipe), not a regular file";
  if (S_ISCHR(mode)) return "is a character device, not a regular file";
  if (S_ISBLK(mode)) return "is a block device, not a regular file";
  if (S_ISSOCK(mode)) return "is a socket, not a regular file";
  return "is not a regular file";
}

}  // namespace

std::string notRegularFile(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return "no such file";
    return std::string("cannot be read: ") + std::strerror(errno);
  }
  return kindProblem(st.st_mode);
}

std::string notRegularFile(int fd) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) return std::string("cannot be read: ") + std::strerror(errno);
  return kindProblem(st.st_mode);
}

}  // namespace coloc
