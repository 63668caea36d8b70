// Where the `coloc` binary finds its data (the scripts it runs, the cases, the docs), so that an
// installed copy (cmake --install) does not depend on the source tree it was built from.
#pragma once

#include <filesystem>

namespace coloc {

/// The folder holding scripts/ (snapshot.py, provenance.py) and cases/:
///   - installed: PREFIX/share/coloc beside the binary's PREFIX/bin (found through
///     /proc/self/exe, so a moved prefix still works), when it holds scripts/;
///   - otherwise (the build tree): the source tree's bench/ (the path compiled in).
/// No environment variable: the driver reads none (CTest no_env_hooks_in_libraries).
std::filesystem::path dataDir();

}  // namespace coloc
