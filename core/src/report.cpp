#include "coloc/core/report.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "coloc/core/files.hpp"

namespace coloc {

Report::Report(const std::string& caseSource, const Json& resolvedConfig) {
  json_["coloc_version"] = kVersion;
  json_["case"] = caseSource;
  json_["config"] = resolvedConfig;
}

void Report::set(const std::string& path, Json value) {
  Json* node = &json_;
  std::size_t start = 0;
  while (true) {
    const auto dot = path.find('.', start);
    const std::string key =
        path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (dot == std::string::npos) {
      (*node)[key] = std::move(value);
      return;
    }
    node = &(*node)[key];
    if (!node->is_object()) *node = Json::object();
    start = dot + 1;
  }
}

void Report::merge(const Json& object) {
  for (auto& [k, v] : object.items()) {
    if (json_.contains(k) && json_[k].is_object() && v.is_object()) {
      for (auto& [k2, v2] : v.items()) json_[k][k2] = v2;
    } else {
      json_[k] = v;
    }
  }
}

void Report::addMemory(const Comm& comm) {
  const long long rss = peakRssBytes();
  set("memory.peak_rss_bytes_max", comm.max(rss));
  set("memory.peak_rss_bytes_sum", comm.sum(rss));
}

void makeDirectories(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError("cannot create directory '" + dir + "': " + ec.message());
}

std::string Report::write(const Comm& comm, const std::string& dir) const {
  const std::string path = (std::filesystem::path(dir) / "report.json").string();
  const std::string tmp = path + ".tmp";
  std::string err;
  if (comm.isRoot()) {
    // Through report.json.tmp, renamed once every rank has agreed: a failure (a full disk, a
    // rank that fails meanwhile) never leaves a partial or an untrue report.json; the close is
    // checked (the last buffer is written there).
    try {
      makeDirectories(dir);
      // a regular file only, never through a symbolic link (coloc/core/files.hpp)
      if (const std::string why = writeTargetProblem(path); !why.empty()) throw IoError(why);
      const std::string text = json_.dump(2) + "\n";
      const int fd = createFresh(tmp);
      int e = writeAll(fd, text);
      if (::close(fd) != 0 && e == 0) e = errno;
      if (e != 0) throw IoError("error writing '" + tmp + "': " + std::strerror(e));
    } catch (const std::exception& e) {
      err = e.what();
    }
  }
  std::string msg = comm.firstError(err, 4);
  if (msg.empty() && comm.isRoot()) err = publishFile(tmp, path);
  if (msg.empty()) msg = comm.firstError(err, 4);
  if (!msg.empty()) {
    if (comm.isRoot()) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
    }
    throw IoError(msg);
  }
  return path;
}

}  // namespace coloc
