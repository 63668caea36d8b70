// coloc/core/fault.hpp — named points where a test can inject a failure.
//
// The solvers and the driver mark their phases with fault::point("fluid", step). In the `coloc`
// binary nothing installs a hook, so a point is one test of a null pointer and does nothing. The
// test build of the driver (target coloc_faults, tests/robustness/fault_hook.cpp) installs one
// that fails one chosen rank at one chosen point and step (an error, an I/O error, an unexpected
// exception, or SIGKILL), to check that every failure ends every rank (docs/robustness.md).
#pragma once

namespace coloc::fault {

using Hook = void (*)(const char* point, long long step);

/// Installs the hook (tests only); nullptr removes it.
void install(Hook hook);

/// A fault point: calls the hook if one is installed.
void point(const char* name, long long step);

}  // namespace coloc::fault
