// Where a run comes from (coloc/core/provenance.hpp).
#include "coloc/core/provenance.hpp"

#include <mpi.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <ctime>
#include <fstream>
#include <vector>

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

/// The CPUs this process may run on (its affinity mask: what mpirun --bind-to or srun
/// --cpu-bind left it), as a list "0-3,8".
std::string cpuListText(const cpu_set_t& set) {
  std::string text;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (!CPU_ISSET(c, &set)) continue;
    int e = c;
    while (e + 1 < CPU_SETSIZE && CPU_ISSET(e + 1, &set)) ++e;
    if (!text.empty()) text += ',';
    text += std::to_string(c);
    if (e > c) text += '-' + std::to_string(e);
    c = e;
  }
  return text.empty() ? "unknown" : text;
}

/// How the ranks of one node are placed on its CPUs (collective over `node`, the ranks of one
/// node): 0 each rank on CPUs of its own ("exclusive"; one rank: bound to fewer than the
/// node's CPUs), 1 ranks whose CPU sets overlap without being equal ("overlapping"), 2 every
/// rank free to run on the same CPUs ("none": not bound).
int nodeBinding(MPI_Comm node, const cpu_set_t& mine, long long online) {
  int size = 1;
  MPI_Comm_size(node, &size);
  std::vector<cpu_set_t> all(static_cast<std::size_t>(size));
  MPI_Allgather(&mine, sizeof(cpu_set_t), MPI_BYTE, all.data(), sizeof(cpu_set_t), MPI_BYTE, node);
  if (size == 1) return CPU_COUNT(&mine) < online ? 0 : 2;
  bool equal = true, disjoint = true;
  for (int a = 0; a < size; ++a)
    for (int b = a + 1; b < size; ++b) {
      cpu_set_t both;
      CPU_AND(&both, &all[static_cast<std::size_t>(a)], &all[static_cast<std::size_t>(b)]);
      if (CPU_COUNT(&both) > 0) disjoint = false;
      if (!CPU_EQUAL(&all[static_cast<std::size_t>(a)], &all[static_cast<std::size_t>(b)]))
        equal = false;
    }
  return disjoint ? 0 : (equal ? 2 : 1);
}

/// Open MPI's mpi_yield_when_idle (a rank waiting in MPI yields its core instead of polling) as
/// the library has it, read through the MPI tool interface (MPI_T): true or false, or "unknown"
/// where the library has no such control variable (another MPI, SimGrid SMPI).
Json mpiYieldWhenIdle() {
#if COLOC_MPI_T
  int provided = 0;
  if (MPI_T_init_thread(MPI_THREAD_SINGLE, &provided) != MPI_SUCCESS) return "unknown";
  Json value = "unknown";
  int index = -1;
  if (MPI_T_cvar_get_index("mpi_yield_when_idle", &index) == MPI_SUCCESS) {
    char name[256];
    char desc[1024];
    int nameLen = sizeof name, descLen = sizeof desc, verbosity = 0, bind = 0, scope = 0;
    MPI_Datatype type = MPI_DATATYPE_NULL;
    MPI_T_enum enumType{};
    MPI_T_cvar_handle handle{};
    int count = 0;
    if (MPI_T_cvar_get_info(index, name, &nameLen, &verbosity, &type, &enumType, desc, &descLen,
                            &bind, &scope) == MPI_SUCCESS &&
        MPI_T_cvar_handle_alloc(index, nullptr, &handle, &count) == MPI_SUCCESS) {
      alignas(8) unsigned char buffer[64] = {};
      if (count == 1 && MPI_T_cvar_read(handle, buffer) == MPI_SUCCESS) {
        if (type == MPI_INT) {
          int v = 0;
          std::memcpy(&v, buffer, sizeof v);
          value = v != 0;
        } else if (type == MPI_C_BOOL) {
          bool v = false;
          std::memcpy(&v, buffer, sizeof v);
          value = v;
        }
      }
      MPI_T_cvar_handle_free(&handle);
    }
  }
  MPI_T_finalize();
  return value;
#else
  return "unknown";
#endif
}

}  // namespace

std::string buildDescription() {
  const std::string dirty = COLOC_GIT_DIRTY;
  std::string text = std::string("coloc ") + kVersion + "\n";
  text += std::string("  git commit:  ") + COLOC_GIT_COMMIT +
          (dirty == "true" ? " (with uncommitted changes)" : "") + "\n";
  text += std::string("  compiler:    ") + COLOC_CXX_COMPILER + ", " + COLOC_BUILD_TYPE + "\n";
  text += std::string("  flags:       ") + COLOC_CXX_FLAGS + "\n";
  text += "  MPI:         " + mpiLibraryVersion() + "\n";
  return text;
}

Json provenance(const Comm& comm, const std::string& commandLine) {
  // The ranks of each node (a shared-memory communicator) against that node's cores.
  const long online = ::sysconf(_SC_NPROCESSORS_ONLN);
  const long long cores = online > 0 ? online : 1;
  // Where this rank may run (its affinity mask), and how the ranks of its node share the CPUs.
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  const bool haveMask = ::sched_getaffinity(0, sizeof cpus, &cpus) == 0;
  if (!haveMask)
    for (long long c = 0; c < std::min<long long>(cores, CPU_SETSIZE); ++c) CPU_SET(c, &cpus);
  MPI_Comm node = MPI_COMM_NULL;
  MPI_Comm_split_type(comm.raw(), MPI_COMM_TYPE_SHARED, comm.rank(), MPI_INFO_NULL, &node);
  int onNode = 1, nodeRank = 0, binding = 2;
  if (node != MPI_COMM_NULL) {
    MPI_Comm_size(node, &onNode);
    MPI_Comm_rank(node, &nodeRank);
    binding = nodeBinding(node, cpus, cores);
    MPI_Comm_free(&node);
  }
  const int over = comm.max(onNode > cores ? 1 : 0);
  const long long nodes = comm.sum(nodeRank == 0 ? 1LL : 0LL);
  const long long perNode = comm.max(static_cast<long long>(onNode));
  const long long perNodeMin = comm.min(static_cast<long long>(onNode));
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
  // What the MPI library was told that changes timings: the ranks a node, how they sit on its
  // CPUs, whether a waiting rank yields its core (docs/benchmarks.md, provenance.mpi_env).
  Json env = Json::object();
  env["ranks_per_node_min"] = perNodeMin;
  env["ranks_per_node_max"] = perNode;
  static const char* const kBinding[3] = {"exclusive", "overlapping", "none"};
  env["binding"] = simulated ? "simulated" : kBinding[std::clamp(comm.max(binding), 0, 2)];
  const long long nCpus = CPU_COUNT(&cpus);
  env["cpus_per_rank_min"] = comm.min(nCpus);
  env["cpus_per_rank_max"] = comm.max(nCpus);
  env["cpus_rank0"] = comm.broadcast(haveMask ? cpuListText(cpus) : std::string("unknown"));
  const Json yield = simulated ? Json("simulated") : mpiYieldWhenIdle();
  env["yield_when_idle"] = Json::parse(comm.broadcast(yield.dump()));  // rank 0's
  p["mpi_env"] = env;
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
