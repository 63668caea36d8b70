// What a file given for reading must be (coloc/core/files.hpp).
#include "coloc/core/files.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "coloc/core/error.hpp"

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

// ---- files coloc writes (coloc/core/files.hpp) ---------------------------------------------

namespace coloc {
namespace {

std::string kindOf(mode_t mode) {
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string quoted(const std::string& path) {
  return "'" + path + "'";
}

/// The name limit of the folder that holds `path` (255 on the usual file systems).
long nameLimit(const std::string& path) {
  const auto slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "."
                          : slash == 0               ? "/"
                                                     : path.substr(0, slash);
  errno = 0;
  const long n = ::pathconf(dir.c_str(), _PC_NAME_MAX);
  return n > 0 ? n : 255;
}

}  // namespace

std::string writeTargetProblem(const std::string& path, bool viaTmp) {
  if (path.empty()) return "'' is an empty file name";
  const auto slash = path.rfind('/');
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  if (name.empty() || name == "." || name == "..")
    return quoted(path) + " names a folder, not a file";
  const std::size_t extra = viaTmp ? 4 : 0;  // NAME.tmp
  const std::size_t withTmp = name.size() + extra;
  if (static_cast<long>(withTmp) > nameLimit(path))
    return fmt::format(
        "{} has a file name of {} bytes ({} with '.tmp'): the file system takes at "
        "most {}",
        quoted(path), name.size(), withTmp, nameLimit(path));
  // the path as the libraries see it, from the root (a relative one grows by the working folder)
  std::size_t full = path.size();
  if (path[0] != '/') {
    std::error_code ec;
    full = std::filesystem::absolute(path, ec).string().size();
    if (ec) full = path.size();
  }
  if (full + extra > kMaxWritePathBytes)
    return fmt::format(
        "'{:.60}...' is a path of {} bytes from the root: coloc writes paths of at "
        "most {} bytes (with '.tmp'); give a shorter folder",
        path, full, kMaxWritePathBytes);
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return "";  // nothing there (or the write will say)
  if (S_ISREG(st.st_mode)) return "";
  return quoted(path) + " is " + kindOf(st.st_mode) +
         ", not a regular file: coloc writes only regular files and never writes through or "
         "replaces anything else (remove it, or write elsewhere)";
}

int writeAll(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return errno;
    if (n == 0) return EIO;
    done += static_cast<std::size_t>(n);
  }
  return 0;
}

int createFresh(const std::string& tmp) {
  // A stale temporary of coloc's own name (a file, or a link put there) is removed; anything else
  // there (a folder, a FIFO, ...) or a name too long refuses the write.
  struct stat st {};
  if (::lstat(tmp.c_str(), &st) == 0 && (S_ISREG(st.st_mode) || S_ISLNK(st.st_mode))) {
    if (::unlink(tmp.c_str()) != 0 && errno != ENOENT)
      throw IoError(fmt::format("cannot remove the stale '{}': {}", tmp, std::strerror(errno)));
  } else if (const std::string why = writeTargetProblem(tmp, false); !why.empty()) {
    throw IoError(why);
  }
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) throw IoError(fmt::format("cannot create '{}': {}", tmp, std::strerror(errno)));
  return fd;
}

int openForAppend(const std::string& path) {
  if (const std::string why = writeTargetProblem(path); !why.empty()) throw IoError(why);
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) throw IoError(fmt::format("cannot open '{}': {}", path, std::strerror(errno)));
  if (const std::string why = notRegularFile(fd); !why.empty()) {
    ::close(fd);
    throw IoError(fmt::format("cannot write '{}': it {}", path, why));
  }
  return fd;
}

std::string publishFile(const std::string& tmp, const std::string& path) {
  std::string err;
  if (const std::string why = writeTargetProblem(path); !why.empty())
    err = why;
  else if (::rename(tmp.c_str(), path.c_str()) != 0)
    err = fmt::format("cannot rename '{}' to '{}': {}", tmp, path, std::strerror(errno));
  if (!err.empty()) ::unlink(tmp.c_str());
  return err;
}

void writeFileWhole(const std::string& path, const std::string& text) {
  if (const std::string why = writeTargetProblem(path); !why.empty()) throw IoError(why);
  const std::string tmp = path + ".tmp";
  const int fd = createFresh(tmp);
  int e = writeAll(fd, text);
  if (::close(fd) != 0 && e == 0) e = errno;
  if (e != 0) {
    ::unlink(tmp.c_str());
    throw IoError(fmt::format("cannot write '{}': {}", tmp, std::strerror(e)));
  }
  if (const std::string err = publishFile(tmp, path); !err.empty()) throw IoError(err);
}

void checkUserFile(const std::string& key, const std::string& path, const std::string& magic) {
  if (const std::string why = writeTargetProblem(path); !why.empty()) throw ConfigError(key, why);
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return;  // nothing there
  // a regular file (writeTargetProblem): of our kind?
  std::string head(magic.size(), '\0');
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  const ssize_t n = fd >= 0 ? ::read(fd, head.data(), head.size()) : -1;
  if (fd >= 0) ::close(fd);
  if (n != static_cast<ssize_t>(magic.size()) || head != magic)
    throw ConfigError(key, fmt::format("'{}' exists and is not a file of this kind (it does not "
                                       "start with '{}'): coloc replaces only a file it could "
                                       "have written; remove it, or give another name",
                                       path, magic));
}

void writeUserFile(const std::string& key, const std::string& path, const std::string& text,
                   const std::string& magic) {
  checkUserFile(key, path, magic);
  // PATH.tmp, made new (O_EXCL, never through a link): a file of that name is the user's, not
  // removed, and refuses the write.
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int e = errno;
    throw IoError(e == EEXIST ? fmt::format("cannot create '{}': something of that name exists "
                                            "(coloc writes '{}' through it): remove it",
                                            tmp, path)
                              : fmt::format("cannot create '{}': {}", tmp, std::strerror(e)));
  }
  int e = writeAll(fd, text);
  if (::close(fd) != 0 && e == 0) e = errno;
  if (e != 0) {
    ::unlink(tmp.c_str());
    throw IoError(fmt::format("cannot write '{}': {}", path, std::strerror(e)));
  }
  if (const std::string err = publishFile(tmp, path); !err.empty()) throw IoError(err);
}

}  // namespace coloc
