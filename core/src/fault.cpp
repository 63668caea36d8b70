#include "coloc/core/fault.hpp"

#include <atomic>

namespace coloc::fault {
namespace {
std::atomic<Hook> installed{nullptr};  // set only by a test executable
}  // namespace

void install(Hook hook) {
  installed.store(hook);
}

void point(const char* name, long long step) {
  if (const Hook h = installed.load(std::memory_order_relaxed)) h(name, step);
}

}  // namespace coloc::fault
