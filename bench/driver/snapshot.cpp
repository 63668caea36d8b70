// output.snapshot: OUT/snapshot.png (snapshot.hpp).
#include "snapshot.hpp"

#include <cstdio>
#include <filesystem>

#include "coloc/io/output.hpp"

namespace coloc {

void drawSnapshot(const Config& cfg, const std::string& outDir, bool quiet, RunLog& log) {
  const OutputOptions o = outputOptionsFromConfig(cfg, outDir);
  if (!cfg.boolean("output.snapshot") || !o.fields || o.intervalSteps <= 0) return;
  namespace fs = std::filesystem;
  const fs::path script = fs::path(COLOC_SOURCE_DIR) / "bench" / "scripts" / "snapshot.py";
  const char* python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  auto quote = [](const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  const std::string png = (fs::path(outDir) / "snapshot.png").string();
  const std::string cmd = std::string(python) + " " + quote(script.string()) + " " + quote(o.dir) +
                          " --png " + quote(png) + " --report " +
                          quote((fs::path(outDir) / "report.json").string()) + " 2>&1";
  std::fflush(stdout);
  // What the script says goes to the terminal (unless --quiet) and the log.
  int rc = -1;
  if (std::FILE* pipe = ::popen(cmd.c_str(), "r")) {
    char line[1024];
    while (std::fgets(line, sizeof line, pipe))
      if (quiet)
        log.file("{}", line);
      else
        log.out("{}", line);
    rc = ::pclose(pipe);
  }
  if (rc != 0)
    log.err(
        "coloc: warning: no snapshot.png ({} exited with status {}); the run's output "
        "is complete (set output.snapshot=false to skip the picture)\n",
        script.string(), rc);
}

}  // namespace coloc
