// The HDF5 functions of coloc/io/h5io.hpp in a build without HDF5 (the SimGrid SMPI build,
// -DCOLOC_SMPI=ON: parallel HDF5 is linked to Open MPI and cannot run under SMPI). Each one
// throws coloc::Error on every rank that calls it; the driver refuses the keys that would need
// a file before a run starts (coloc/coupling/case_checks.hpp), so these are a last guard.
#include <cstdint>
#include <string>
#include <vector>

#include "coloc/core/error.hpp"
#include "coloc/io/h5io.hpp"
#include "coloc/io/library_version.hpp"

namespace coloc {
namespace {

/// `what`: the dataset or object, or "" where the caller names the file (create, openRead).
[[noreturn]] void unavailable(const std::string& what) {
  throw Error((what.empty() ? std::string() : what + ": ") +
              "HDF5 files are not available in this build of coloc (SimGrid SMPI, "
              "COLOC_SMPI=ON); run the Open MPI build for output, checkpoints and restarts");
}

}  // namespace

bool hdf5Available() {
  return false;
}
std::string hdf5Version() {
  return "none (SimGrid SMPI build)";
}

H5File H5File::create(const Comm&, const std::string&, bool) {
  unavailable("");
}
H5File H5File::openRead(const Comm&, const std::string&) {
  unavailable("");
}
H5File::H5File(H5File&& o) noexcept {
  *this = std::move(o);
}
H5File& H5File::operator=(H5File&& o) noexcept {
  comm_ = o.comm_;
  path_ = std::move(o.path_);
  return *this;
}
H5File::~H5File() = default;
void H5File::release() noexcept {}
void H5File::close() {}
void H5File::createGroup(const std::string& path) {
  unavailable(path);
}
bool H5File::exists(const std::string& path) const {
  unavailable(path);
}
std::vector<long long> H5File::shape(const std::string& dataset) const {
  unavailable(dataset);
}
void H5File::setAttribute(const std::string& object, const std::string&, double) {
  unavailable(object);
}
void H5File::setIntAttribute(const std::string& object, const std::string&, long long) {
  unavailable(object);
}
void H5File::setAttribute(const std::string& object, const std::string&, const std::string&) {
  unavailable(object);
}
void H5File::setAttribute(const std::string& object, const std::string&, std::span<const double>) {
  unavailable(object);
}
double H5File::attributeDouble(const std::string& object, const std::string&) const {
  unavailable(object);
}
long long H5File::attributeInt(const std::string& object, const std::string&) const {
  unavailable(object);
}
std::string H5File::attributeString(const std::string& object, const std::string&) const {
  unavailable(object);
}
std::vector<double> H5File::attributeDoubles(const std::string& object, const std::string&) const {
  unavailable(object);
}

void writeCellField(H5File&, const std::string& path, const Decomposition&, const CellField&) {
  unavailable(path);
}
void readCellField(H5File&, const std::string& path, const Decomposition&, CellField&) {
  unavailable(path);
}
void writeCellVector(H5File&, const std::string& path, const Decomposition&, const CellField&,
                     const CellField&, const CellField&) {
  unavailable(path);
}
void readCellVector(H5File&, const std::string& path, const Decomposition&, CellField&, CellField&,
                    CellField&) {
  unavailable(path);
}
void writeFaceComponent(H5File&, const std::string& path, const Decomposition&, int,
                        const Field3<double>&) {
  unavailable(path);
}
void readFaceComponent(H5File&, const std::string& path, const Decomposition&, int,
                       Field3<double>&) {
  unavailable(path);
}
void writeParticleArray(H5File&, const std::string& path, std::span<const double>) {
  unavailable(path);
}
void writeParticleArray(H5File&, const std::string& path, std::span<const std::int64_t>) {
  unavailable(path);
}
void writeParticleArray(H5File&, const std::string& path, std::span<const int>) {
  unavailable(path);
}
void writeParticleVec3(H5File&, const std::string& path, Vec3Span) {
  unavailable(path);
}
template <class T>
std::vector<T> readParticleArray(H5File&, const std::string& path, const RowRange&) {
  unavailable(path);
}
template std::vector<double> readParticleArray<double>(H5File&, const std::string&,
                                                       const RowRange&);
template std::vector<std::int64_t> readParticleArray<std::int64_t>(H5File&, const std::string&,
                                                                   const RowRange&);
template std::vector<int> readParticleArray<int>(H5File&, const std::string&, const RowRange&);
std::array<std::vector<double>, 3> readParticleVec3(H5File&, const std::string& path,
                                                    const RowRange&) {
  unavailable(path);
}

}  // namespace coloc
