// coloc/core/files.hpp — what a file given for reading must be (a case file, a --restart
// checkpoint): a regular file, checked with stat() before it is opened, so that a FIFO, a
// device or a socket given by mistake is refused with its name instead of blocking the run
// (docs/robustness.md).
#pragma once

#include <string>

namespace coloc {

/// "" when `path` names a regular file (a symbolic link to one is fine); otherwise why not:
/// "no such file", or the end of a sentence that starts with the path ("is a directory, not a
/// file", "is a FIFO (named pipe), not a regular file", ...). Rank-local.
std::string notRegularFile(const std::string& path);

/// The same for an open descriptor (after open(), against a file swapped in meanwhile).
std::string notRegularFile(int fd);

}  // namespace coloc
