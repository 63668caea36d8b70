// The folders of a `coloc run`: lock, checks, clean-up (run_folder.hpp).
#include "run_folder.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>

#include "coloc/core/error.hpp"
#include "coloc/core/files.hpp"

namespace coloc {
namespace fs = std::filesystem;

FolderLocks::~FolderLocks() {
  for (int fd : fds_) ::close(fd);  // releases the lock; the file stays (see lock())
}

void FolderLocks::lock(const std::string& dir, const std::string& key,
                       const std::string& casePath) {
  const std::string path = (fs::path(dir) / kRunLockFile).string();
  // The file is never removed: removing it at the end would let a run that opened it meanwhile
  // lock a file no one else sees. Holding the flock, not the file's presence, is the lock, so a
  // run that was killed leaves nothing stale.
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd < 0)
    throw IoError("cannot create the lock file '" + path +
                  "' of the output folder: " + std::strerror(errno));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    if (e != EWOULDBLOCK) {
      ::close(fd);
      throw IoError("cannot lock '" + path + "' (the output folder's lock): " + std::strerror(e));
    }
    char buf[512];
    const ssize_t n = ::pread(fd, buf, sizeof buf - 1, 0);
    ::close(fd);
    std::string holder = n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : "";
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == '\r')) holder.pop_back();
    if (holder.empty()) holder = "a process that has not yet written its name";
    throw ConfigError(key, "the output folder '" + dir + "' is in use by another coloc run (" +
                               holder + "; lock file " + path +
                               "): wait until it ends, or give another folder");
  }
  char host[256] = "?";
  ::gethostname(host, sizeof host - 1);
  host[sizeof host - 1] = '\0';
  const std::time_t now = std::time(nullptr);
  char when[64] = "?";
  std::tm tm{};
  if (::gmtime_r(&now, &tm)) std::strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S UTC", &tm);
  const std::string who =
      fmt::format("pid {} on host {}, started {}, case {}\n", ::getpid(), host, when, casePath);
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, who.data(), who.size(), 0) < 0) {
    // The lock is held; only the note of who holds it is missing.
  }
  fds_.push_back(fd);
}

namespace {

/// `child` lies in `parent` (both canonical) or is it.
bool inside(const fs::path& child, const fs::path& parent) {
  const fs::path rel = child.lexically_relative(parent);
  return !rel.empty() && *rel.begin() != "..";
}

}  // namespace

void checkRunFiles(const RunFolders& f, const std::string& restart) {
  const fs::path data = fs::canonical(f.dataDir);
  const fs::path out = fs::canonical(f.outDir);
  const fs::path rel = fs::path(f.checkpointFile).lexically_normal();
  // The checkpoint's folder, with every symbolic link on the way resolved: still in output.dir.
  const fs::path ckDir = fs::weakly_canonical(data / rel.parent_path());
  if (!inside(ckDir, data))
    throw ConfigError("output.checkpoint_file",
                      "'" + f.checkpointFile + "' leaves the run's output folder '" + f.dataDir +
                          "' through a symbolic link (its folder is '" + ckDir.string() +
                          "'): a checkpoint is written inside the output folder");
  if (restart.empty()) return;
  // --restart is read, and may be anywhere; but not a file this run writes over or removes
  // (other than its own checkpoint, which a restart in place continues).
  std::error_code ec;
  const fs::path r = fs::weakly_canonical(restart, ec);
  if (ec) return;  // the restart's own check names the problem
  const fs::path dir = r.parent_path();
  const std::string name = r.filename().string();
  if (dir == ckDir && matchesStepPattern(name, rel.filename().string())) return;
  if (dir != data && dir != out && dir != ckDir) return;
  if (const std::string role = runFileRole(name); !role.empty())
    throw ConfigError("--restart", "'" + restart + "' is " + role +
                                       " in this run's output folder, which the run writes or "
                                       "removes: copy it elsewhere and restart from the copy");
}

void checkWritePaths(const RunFolders& f) {
  const fs::path out(f.outDir), data(f.dataDir);
  const auto check = [](const std::string& key, const fs::path& path) {
    if (const std::string why = writeTargetProblem(path.string()); !why.empty())
      throw ConfigError(key, why);
  };
  for (const char* name : {"report.json", "series.csv", "log.txt", "snapshot.png",
                           "rebalance.tmp.h5", "rebalance.tmp.h5.tmp"})
    check("--out", out / name);
  // the output of the largest step a run can have (19 digits): the longest names
  const std::string big(19, '9');
  for (const std::string& name : {std::string("fields.xmf"), std::string("particles.xmf"),
                                  "fields_" + big + ".h5", "particles_" + big + ".h5"})
    check("output.dir", data / name);
  CheckpointOptions ck;
  ck.path = (data / fs::path(f.checkpointFile).lexically_normal()).string();
  for (const long long step : {0LL, 999999999999999999LL}) {
    check("output.checkpoint_file", ck.pathAt(step));
    check("output.checkpoint_file", failedCheckpointPath(ck.pathAt(step)));
  }
}

bool restartInFolders(const RunFolders& f, const std::string& restart) {
  if (restart.empty()) return false;
  std::error_code ec;
  const fs::path dir = fs::weakly_canonical(restart, ec).parent_path();
  if (ec) return false;
  const fs::path rel = fs::path(f.checkpointFile).lexically_normal();
  for (const fs::path& d :
       {fs::path(f.outDir), fs::path(f.dataDir), fs::path(f.dataDir) / rel.parent_path()}) {
    const fs::path c = fs::weakly_canonical(d, ec);
    if (!ec && c == dir) return true;
  }
  return false;
}

std::vector<std::string> previousRunFiles(const RunFolders& f) {
  std::error_code ec;
  const fs::path out(f.outDir), data(f.dataDir);
  const fs::path rel = fs::path(f.checkpointFile).lexically_normal();
  const fs::path ckDir = data / rel.parent_path();
  const std::string ck = rel.filename().string();
  const std::string failed = fs::path(failedCheckpointPath(ck)).string();
  const auto startsEnds = [](const std::string& s, const std::string& head,
                             const std::string& tail) {
    return s.size() > head.size() + tail.size() && s.compare(0, head.size(), head) == 0 &&
           s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
  };
  const auto isOutFile = [&](const std::string& name) {
    return name == "report.json" || name == "series.csv" || name == "log.txt" ||
           name == "snapshot.png" || startsEnds(name, "render_", ".png");
  };
  const auto isDataFile = [&](const std::string& name) {
    return name == "fields.xmf" || name == "particles.xmf" ||
           matchesStepPattern(name, "fields_{step}.h5") ||
           matchesStepPattern(name, "particles_{step}.h5");
  };
  const auto isCheckpoint = [&](const std::string& name) {
    return matchesStepPattern(name, ck) || matchesStepPattern(name, failed);
  };
  std::vector<std::string> found;
  std::vector<fs::path> seen;
  const auto scan = [&](const fs::path& dir) {
    if (!fs::is_directory(dir, ec)) return;
    for (const fs::path& s : seen)
      if (fs::equivalent(s, dir, ec)) return;
    seen.push_back(dir);
    const bool isOut = fs::equivalent(dir, out, ec);
    const bool isData = fs::equivalent(dir, data, ec);
    const bool isCk = fs::equivalent(dir, ckDir, ec);
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      if (entry.is_directory(ec)) continue;
      const std::string name = entry.path().filename().string();
      if ((isOut && isOutFile(name)) || (isData && isDataFile(name)) ||
          (isCk && isCheckpoint(name)))
        found.push_back(entry.path().string());
    }
  };
  scan(out);
  scan(data);
  scan(ckDir);
  std::sort(found.begin(), found.end());
  return found;
}

void refuseMixedRuns(const RunFolders& f, const std::vector<std::string>& files) {
  if (files.empty()) return;
  std::string list;
  const std::size_t shown = std::min<std::size_t>(files.size(), 6);
  for (std::size_t i = 0; i < shown; ++i) {
    const fs::path rel = fs::path(files[i]).lexically_relative(f.outDir);
    list += (i ? ", " : "") + (rel.empty() || *rel.begin() == ".." ? files[i] : rel.string());
  }
  if (files.size() > shown) list += fmt::format(" and {} more", files.size() - shown);
  std::error_code ec;
  const std::string where = fs::equivalent(f.outDir, f.dataDir, ec)
                                ? "the output folder '" + f.outDir + "' holds"
                                : "the output folders '" + f.outDir + "' (--out) and '" +
                                      f.dataDir + "' (output.dir) hold";
  throw ConfigError("--out", where + " the files of another run (" + list +
                                 "): a run does not mix its files with another's; give "
                                 "--overwrite to remove them first, another --out folder, or "
                                 "--restart a checkpoint in this folder to continue that run");
}

void removeRunFiles(const std::vector<std::string>& files) {
  for (const std::string& path : files) {
    std::error_code ec;
    fs::remove(path, ec);
    if (ec)
      throw IoError("--overwrite: cannot remove '" + path +
                    "' of the earlier run: " + ec.message());
  }
}

void removePreviousReport(const RunFolders& f) {
  std::error_code ec;
  for (const char* name : {"report.json", "series.csv"}) fs::remove(fs::path(f.outDir) / name, ec);
}

void removeStaleFiles(const RunFolders& f) {
  std::error_code ec;
  const fs::path out(f.outDir), data(f.dataDir);
  for (const char* name :
       {"report.json.tmp", "series.csv.tmp", "rebalance.tmp.h5", "rebalance.tmp.h5.tmp"})
    fs::remove(out / name, ec);
  const fs::path rel = fs::path(f.checkpointFile).lexically_normal();
  const std::string ck = rel.filename().string() + ".tmp";
  const std::string failed = fs::path(failedCheckpointPath(rel.filename().string())).string();
  const auto isStaleTmp = [&](const std::string& name, bool dataFolder, bool ckFolder) {
    if (dataFolder && (name == "fields.xmf.tmp" || name == "particles.xmf.tmp" ||
                       matchesStepPattern(name, "fields_{step}.h5.tmp") ||
                       matchesStepPattern(name, "particles_{step}.h5.tmp")))
      return true;
    return ckFolder && (matchesStepPattern(name, ck) || matchesStepPattern(name, failed + ".tmp"));
  };
  const fs::path ckDir = data / rel.parent_path();
  const bool same = fs::equivalent(data, ckDir, ec);
  const auto scan = [&](const fs::path& dir, bool dataFolder, bool ckFolder) {
    if (!fs::is_directory(dir, ec)) return;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      const std::string name = entry.path().filename().string();
      if (isStaleTmp(name, dataFolder, ckFolder)) fs::remove(entry.path(), ec);
    }
  };
  scan(data, true, same);
  if (!same) scan(ckDir, false, true);
}

}  // namespace coloc
