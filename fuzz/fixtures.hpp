// The plan manifests the manifest-bound readers are fuzzed against (fuzz/fixtures/, written by
// `probeloop plan`, see fuzz/README.md), read once per process.
#pragma once
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "parts/plan_manifest.hpp"

#ifndef PROBELOOP_FUZZ_FIXTURES
#error "PROBELOOP_FUZZ_FIXTURES: the fuzz/fixtures folder (set by fuzz/CMakeLists.txt)"
#endif

namespace probeloop::fuzz {

// A missing or unreadable fixture is the harness's failure, not the reader's: stop with a
// message rather than let the exception look like a finding.
inline parts::PlanManifest readFixture(const std::string& name) {
  const std::string path = std::string(PROBELOOP_FUZZ_FIXTURES) + "/" + name;
  try {
    return parts::readManifest(path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz harness: fixture %s: %s (fuzz/make_output_seeds.sh writes it)\n", path.c_str(), e.what());
    std::abort();
  }
}

// The sphere artifact's plan (LinuxCNC dialect): 4 positions, the campaign's cycles.
inline const parts::PlanManifest& sphereManifest() {
  static const parts::PlanManifest m = readFixture("sphere_plan.json");
  return m;
}

// The thermal test piece's plan: its features, cut cycles and inspection points.
inline const parts::PlanManifest& ttpManifest() {
  static const parts::PlanManifest m = readFixture("ttp_plan.json");
  return m;
}

}  // namespace probeloop::fuzz
