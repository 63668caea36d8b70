// Where a run comes from (coloc/core/provenance.hpp).
#include "coloc/core/provenance.hpp"

#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <ctime>
#include <fstream>

#include "build_info.hpp"  // generated at configure time (core/CMakeLists.txt)
#include "git_info.hpp"    // generated at build time (cmake/ColocGitInfo.cmake)

namespace coloc {
namespace {

/// The first "model name" of /proc/cpuinfo (x86), else its "Processor"/"CPU part" line
/// (some ARM kernels), else "unknown".
std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line, fallback;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string key = line.substr(0, colon);
    while (!key.empty() && (key.back() == ' ' || key.back() == '\t')) key.pop_back();
    std::string value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(" \t"));
    if (value.empty()) continue;
    if (key == "model name") return value;
    if (fallback.empty() && (key == "Processor" || key == "CPU part" || key == "cpu model"))
      fallback = value;
  }
  return fallback.empty() ? "unknown" : fallback;
}

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  char text[32] = "unknown";
  if (::gmtime_r(&now, &tm)) std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

}  // namespace

Json provenance(const Comm& comm, const std::string& commandLine) {
  // The ranks of each node (a shared-memory communicator) against that node's cores.
  MPI_Comm node = MPI_COMM_NULL;
  MPI_Comm_split_type(comm.raw(), MPI_COMM_TYPE_SHARED, comm.rank(), MPI_INFO_NULL, &node);
  int onNode = 1, nodeRank = 0;
  if (node != MPI_COMM_NULL) {
    MPI_Comm_size(node, &onNode);
    MPI_Comm_rank(node, &nodeRank);
    MPI_Comm_free(&node);
  }
  const long online = ::sysconf(_SC_NPROCESSORS_ONLN);
  const long long cores = online > 0 ? online : 1;
  const int over = comm.max(onNode > cores ? 1 : 0);
  const long long nodes = comm.sum(nodeRank == 0 ? 1LL : 0LL);
  const long long perNode = comm.max(static_cast<long long>(onNode));
  // The cores the run occupies: on each node, its ranks or its cores, whichever is fewer.
  const long long used =
      comm.sum(nodeRank == 0 ? std::min(static_cast<long long>(onNode), cores) : 0LL);

  char host[256] = "unknown";
  ::gethostname(host, sizeof host - 1);
  host[sizeof host - 1] = '\0';
  const std::string mpiText = mpiLibraryVersion();

  Json p = Json::object();
  p["date"] = comm.broadcast(utcNow());
  p["host"] = comm.broadcast(std::string(host));
  p["cpu_model"] = comm.broadcast(cpuModel());
  p["cores"] = comm.max(comm.isRoot() ? cores : 0LL);
  p["ranks"] = comm.size();
  p["nodes"] = nodes;
  p["ranks_per_node_max"] = perNode;
  // Under SimGrid SMPI (docs/smpi.md) the nodes and ranks are the simulated cluster's, each rank
  // on a simulated core of its own; cores and cpu_model are the machine running the simulation.
  const bool simulated = mpiIsSimulated();
  p["simulated"] = simulated;
  p["oversubscribed"] = !simulated && over != 0;
  p["cores_used"] = simulated ? static_cast<long long>(comm.size()) : used;
  p["coloc_version"] = kVersion;
  p["git_commit"] = COLOC_GIT_COMMIT;
  const std::string dirty = COLOC_GIT_DIRTY;
  if (dirty == "unknown")
    p["git_dirty"] = dirty;
  else
    p["git_dirty"] = dirty == "true";
  p["compiler"] = COLOC_CXX_COMPILER;
  p["compiler_flags"] = COLOC_CXX_FLAGS;
  p["build_type"] = COLOC_BUILD_TYPE;
  p["mpi_library"] = mpiText;
  p["command_line"] = commandLine;
  return p;
}

std::string commandLineText(int argc, const char* const* argv) {
  std::string text;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i] ? argv[i] : "";
    bool plain = !a.empty();
    for (char c : a)
      if (!(std::isalnum(static_cast<unsigned char>(c)) ||
            std::string("-_./=:,@+%").find(c) != std::string::npos))
        plain = false;
    if (i) text += ' ';
    if (plain) {
      text += a;
    } else {
      text += '\'';
      for (char c : a) text += c == '\'' ? std::string("'\\''") : std::string(1, c);
      text += '\'';
    }
  }
  return text;
}

}  // namespace coloc
