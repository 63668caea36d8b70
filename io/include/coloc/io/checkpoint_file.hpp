// coloc/io/checkpoint_file.hpp — where restart checkpoints go and when: the options of the case
// keys output.checkpoint_{interval,file,on_failure} (declared with the output keys,
// coloc/io/output.hpp). What a checkpoint holds is written by coupling/checkpoint.hpp through
// coloc/io/h5io.hpp (docs/output.md, "Checkpoints and restart").
#pragma once

#include <string>

#include "coloc/core/config.hpp"

namespace coloc {

/// Restart checkpoints (coupling/checkpoint.hpp writes them).
struct CheckpointOptions {
  long long intervalSteps = 0;  // 0: none
  std::string path;             // the checkpoint file (output.dir / output.checkpoint_file)
  bool onFailure = true;        // write failedCheckpointPath(path) when the run fails
  bool due(long long step) const {
    return intervalSteps > 0 && step > 0 && step % intervalSteps == 0;
  }
  /// The file of the checkpoint at `step`: path with "{step}" replaced by the zero-padded step
  /// (6 digits), e.g. "ck_{step}.h5" -> "ck_000120.h5"; path itself without the placeholder.
  std::string pathAt(long long step) const;
};

/// The checkpoint options of a case (paths resolved like outputOptionsFromConfig). Throws
/// ConfigError naming output.checkpoint_file when checkpointFileProblem() refuses it.
CheckpointOptions checkpointOptionsFromConfig(const Config& cfg, const std::string& runOutDir);

/// Why `file` (output.checkpoint_file) cannot be a checkpoint name; "" when it can. A checkpoint
/// stays inside its folder (output.dir): not empty, not absolute, no ".." part, not a folder;
/// and it is none of the run's own files (runFileRole, with {step} as any step).
std::string checkpointFileProblem(const std::string& file);

/// The lock file of a run's output folder (held by rank 0 while the run lasts).
inline constexpr const char* kRunLockFile = ".coloc.lock";

/// What `name` (a file name, no folder) is among the files a run writes or removes in its
/// folders: "the report (report.json)", "a field output file", "a temporary file of a write in
/// progress (*.tmp)", ...; "" when it is none of them. Checkpoint names are the caller's.
std::string runFileRole(const std::string& name);

/// True when `name` is `pattern` (a file name, no folder) with "{step}" replaced by a step of
/// six or more digits, or `pattern` itself when it has no "{step}".
bool matchesStepPattern(const std::string& name, const std::string& pattern);
/// Where a failed run's state goes: "DIR/checkpoint.h5" -> "DIR/checkpoint.failed.h5".
std::string failedCheckpointPath(const std::string& path);

}  // namespace coloc
