// The plan manifests the manifest-bound readers are fuzzed against (fuzz/fixtures/, written by
// `probeloop plan`, see fuzz/README.md), read once per process.
#pragma once
#include <string>

#include "parts/plan_manifest.hpp"

#ifndef PROBELOOP_FUZZ_FIXTURES
#error "PROBELOOP_FUZZ_FIXTURES: the fuzz/fixtures folder (set by fuzz/CMakeLists.txt)"
#endif

namespace probeloop::fuzz {

// The sphere artifact's plan (LinuxCNC dialect): 4 positions, the campaign's cycles.
inline const parts::PlanManifest& sphereManifest() {
  static const parts::PlanManifest m = parts::readManifest(std::string(PROBELOOP_FUZZ_FIXTURES) + "/sphere_plan.json");
  return m;
}

// The thermal test piece's plan: its features, cut cycles and inspection points.
inline const parts::PlanManifest& ttpManifest() {
  static const parts::PlanManifest m = parts::readManifest(std::string(PROBELOOP_FUZZ_FIXTURES) + "/ttp_plan.json");
  return m;
}

}  // namespace probeloop::fuzz
