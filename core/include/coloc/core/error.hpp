// coloc/core/error.hpp — the one error type of the project.
//
// Input errors (bad case file, bad option) are detected identically on every rank because the
// case text is broadcast from rank 0 and validated everywhere; each rank throws coloc::Error and
// the driver prints the message once (rank 0) and exits non-zero on every rank. Errors that only
// some ranks can see (a particle outside the box, a NaN in one block) go through
// Comm::raiseIfAny(), a collective that turns a local failure into an Error on every rank.
#pragma once

#include <stdexcept>
#include <string>

namespace coloc {

void rememberError(const char* what);  // coloc/core/failure.hpp

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {
    rememberError(this->what());
  }
};

/// A file or directory could not be written (a full disk, no permission, a read-only file
/// system, a file-size limit): the driver exits with status 4 (docs/robustness.md).
class IoError : public Error {
 public:
  explicit IoError(const std::string& what) : Error(what) {}
};

/// Error in the case file or the command line; the message names the key path.
class ConfigError : public Error {
 public:
  ConfigError(const std::string& keyPath, const std::string& problem)
      : Error(keyPath.empty() ? problem : keyPath + ": " + problem), key_(keyPath) {}
  const std::string& key() const { return key_; }

 private:
  std::string key_;
};

}  // namespace coloc
