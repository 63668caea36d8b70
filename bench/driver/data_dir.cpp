// Where the `coloc` binary finds its data (data_dir.hpp).
#include "data_dir.hpp"

#include <system_error>

namespace coloc {

std::filesystem::path dataDir() {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    // COLOC_INSTALLED_DATA: share/coloc relative to bin/ (GNUInstallDirs; bench/CMakeLists.txt).
    const fs::path installed = (exe.parent_path() / COLOC_INSTALLED_DATA).lexically_normal();
    if (fs::is_directory(installed / "scripts", ec)) return installed;
  }
  return fs::path(COLOC_SOURCE_DIR) / "bench";
}

}  // namespace coloc
