// The folders a `coloc run` writes to (--out, output.dir): the lock that keeps a second run out
// while this one lasts, the checks that keep the checkpoint inside its folder and off the run's
// own files and off the --restart file, and the clean-up of what an earlier run of coloc left
// unfinished (docs/robustness.md, "What is kept on disk"). Rank 0 only; the driver agrees on the
// outcome with the other ranks.
#pragma once

#include <string>
#include <vector>

#include "coloc/io/checkpoint_file.hpp"

namespace coloc {

/// The run's folders and the names it writes there.
struct RunFolders {
  std::string outDir;          // --out: report.json, series.csv, snapshot.png, rebalance.tmp.h5
  std::string dataDir;         // output.dir: fields, particles, .xmf and the checkpoint
  std::string checkpointFile;  // output.checkpoint_file, relative to dataDir ({step} kept)
};

/// An exclusive lock (flock) on DIR/.coloc.lock of each folder, held while the object lives
/// (the kernel drops it when the process ends, however it ends: no stale lock). The file says
/// who holds it (pid, host, start time, case).
class FolderLocks {
 public:
  FolderLocks() = default;
  ~FolderLocks();
  FolderLocks(const FolderLocks&) = delete;
  FolderLocks& operator=(const FolderLocks&) = delete;
  /// Locks `dir` (an existing folder); throws ConfigError naming `key` (--out, output.dir) and
  /// the run that holds it when another process does; IoError when the lock file cannot be made.
  void lock(const std::string& dir, const std::string& key, const std::string& casePath);

 private:
  std::vector<int> fds_;
};

/// Throws ConfigError naming output.checkpoint_file when the checkpoint's folder leaves dataDir
/// through a symbolic link, and naming --restart when `restart` is one of the files the run
/// writes or removes in its folders (other than its own checkpoint name). The folders exist.
void checkRunFiles(const RunFolders& f, const std::string& restart);

/// Throws ConfigError naming --out, output.dir or output.checkpoint_file when a file the run
/// writes there cannot be written by coloc's rules (coloc/core/files.hpp): a name or path too
/// long (the output of the largest step included), or something there that is not a regular
/// file (a symbolic link, a folder, a FIFO, a device). Before anything is written.
void checkWritePaths(const RunFolders& f);

/// The restart file `restart` (may be empty) lies in one of the run's folders (--out, output.dir
/// or the checkpoint's folder): the run continues the run that wrote it, in the same folders.
bool restartInFolders(const RunFolders& f, const std::string& restart);

/// The files of an earlier run that coloc knows of in the run's folders, as paths (folder /
/// name), sorted: report.json, series.csv, log.txt, snapshot.png, render_*.png, fields.xmf,
/// particles.xmf, fields_NNNNNN.h5, particles_NNNNNN.h5, the checkpoints of
/// output.checkpoint_file (any {step}) and their failed state. Other programs' files, the lock
/// and the .tmp files of an unfinished write (removeStaleFiles) are not listed.
std::vector<std::string> previousRunFiles(const RunFolders& f);

/// Throws ConfigError naming --out when `files` (previousRunFiles) is not empty: the folder holds
/// another run's files; the message names them (the first few) and the ways out (--overwrite,
/// another folder, --restart of a checkpoint there).
void refuseMixedRuns(const RunFolders& f, const std::vector<std::string>& files);

/// Removes `files` (--overwrite: the earlier run's files, once the new run is set up and before
/// it writes anything of its own).
/// Throws IoError naming the first that cannot be removed.
void removeRunFiles(const std::vector<std::string>& files);

/// Removes the temporary files that only coloc itself makes (report.json.tmp, series.csv.tmp,
/// fields.xmf.tmp, fields_NNNNNN.h5.tmp, <checkpoint>.tmp, rebalance.tmp.h5, ...) and that a
/// killed run left. Nothing else: other programs' files stay. Checkpoints and output are kept.
void removeStaleFiles(const RunFolders& f);

/// Removes the previous report.json and series.csv of --out (a restart in place continues that
/// run: they would mislead about this one). Once the new run is set up.
void removePreviousReport(const RunFolders& f);

}  // namespace coloc
