// coloc/core/files.hpp — what a file given for reading must be (a case file, a --restart
// checkpoint): a regular file, checked with stat() before it is opened, so that a FIFO, a
// device or a socket given by mistake is refused with its name instead of blocking the run
// (docs/robustness.md).
#pragma once

#include <cstddef>
#include <string>

namespace coloc {

/// "" when `path` names a regular file (a symbolic link to one is fine); otherwise why not:
/// "no such file", or the end of a sentence that starts with the path ("is a directory, not a
/// file", "is a FIFO (named pipe), not a regular file", ...). Rank-local.
std::string notRegularFile(const std::string& path);

/// The same for an open descriptor (after open(), against a file swapped in meanwhile).
std::string notRegularFile(int fd);

}  // namespace coloc

// ---- files coloc writes ---------------------------------------------------------------------
//
// One policy for every file coloc writes (report.json, series.csv, log.txt, the HDF5 output and
// checkpoints, the .xmf indexes, plan.csv/plan.json, the SVG of `coloc check --draw`): a
// regular file, in the run's folder or at the path the user named for it. What is there already
// is never written through or replaced unless it is a regular file: a symbolic link is not
// followed (it could lead out of the folder), and a directory, a FIFO, a device or a socket is
// refused by name. A file is written as NAME.tmp (made afresh, never through a link) and renamed
// to NAME when complete; a failure removes the NAME.tmp. Names are checked for length before
// anything is written (docs/robustness.md, "What is kept on disk").

namespace coloc {

/// The longest path coloc writes (bytes, NAME.tmp included): far below PATH_MAX, and within
/// what the MPI-IO layers take (a longer name made Open MPI abort instead of failing).
inline constexpr std::size_t kMaxWritePathBytes = 1024;

/// "" when `path` may be written by coloc (through `path`.tmp and a rename, or appended to);
/// otherwise why not, a sentence that starts with the path in quotes: too long a name (the last
/// part with ".tmp" above the file system's limit, or the whole above kMaxWritePathBytes), or
/// something there that is not a regular file (checked with lstat: a symbolic link counts as
/// not regular). `viaTmp` false: `path` is itself the file written (a NAME.tmp). Rank-local.
std::string writeTargetProblem(const std::string& path, bool viaTmp = true);

/// Creates `tmp` afresh for writing: a stale file or symbolic link of that name (a temporary
/// name of coloc's) is removed first; O_CREAT | O_EXCL | O_NOFOLLOW. Returns the descriptor, or
/// throws IoError naming the file.
int createFresh(const std::string& tmp);

/// Writes all of `text` to `fd` (a short write continued, EINTR retried): 0, or the errno.
int writeAll(int fd, const std::string& text);

/// Opens `path` for appending (created when absent), never through a symbolic link; throws
/// IoError (writeTargetProblem's reason, or the system's) naming the file.
int openForAppend(const std::string& path);

/// Renames `tmp` over `path` when nothing or a regular file is there (lstat); otherwise, or when
/// the rename fails, removes `tmp`. Returns "" or the error (naming both files).
std::string publishFile(const std::string& tmp, const std::string& path);

/// Writes `text` to `path` through `path`.tmp and a rename (createFresh, publishFile); throws
/// IoError naming the file. The directory must exist.
void writeFileWhole(const std::string& path, const std::string& text);

/// Writes `text` to `path`, a file the user named for it (`coloc check --draw PATH`): through
/// PATH.tmp (made new with O_EXCL: one that exists is not removed but refuses the write; removed
/// on a failure) and a rename. What is at `path` is replaced only when it is a regular file that
/// starts with `magic` (a file of the same kind, e.g. "<?xml" for an SVG): the case file, a
/// link, a FIFO or a device given by mistake is refused, naming `key` and the path (IoError for
/// a failed write, ConfigError for a path refused).
void writeUserFile(const std::string& key, const std::string& path, const std::string& text,
                   const std::string& magic);
/// writeUserFile's check of `path` alone (before the work that makes the text).
void checkUserFile(const std::string& key, const std::string& path, const std::string& magic);

}  // namespace coloc
