// Test generator: what the sphere cycle would log on a machine whose C axis carries known
// location errors (no G-code execution yet: the manifest's probing lines are used).
//
// Contract: deterministic for the same manifest, truth and seed; throws InputError for a
// bad truth file and SafetyError when a probing line would miss the displaced sphere
// (the real program would stop there).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/location_errors.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::sim {

struct LocationKeyframe {
  double time_s = 0;
  geometry::LocationErrors errors;
};

// Piecewise linear in time between keyframes, constant outside (zero without keyframes).
geometry::LocationErrors interpolateKeyframes(const std::vector<LocationKeyframe>& k, double time_s);
// A YAML list of keyframes {time, EX0C_um, ..., EC0C_urad} (absent values 0), times
// increasing; InputError with file:line otherwise.
std::vector<LocationKeyframe> readLocationKeyframes(parts::YamlMap& parent, const std::string& key);

// Schema: docs/formats.md#rigid-truth.
struct RigidTruth {
  std::vector<LocationKeyframe> keyframes;  // piecewise linear in time, constant outside
  bool per_point = false;  // errors at each point's time (drift in a cycle) or at cycle start
  double probe_noise_um = 0;  // standard deviation along the probing direction
  bool quantise = true;       // report coordinates at the machine's resolution
  geometry::LocationErrors at(double time_s) const;
};

RigidTruth loadRigidTruth(const std::string& path);

struct SynthCampaign {
  std::string linuxcnc_log, fanuc_dprnt, points_csv, truth_json;
  std::vector<geometry::LocationErrors> truth_per_cycle;  // relative to cycle 1
};

SynthCampaign synthesiseSphereCampaign(const parts::PlanManifest& manifest,
                                       const RigidTruth& truth, std::uint64_t seed);

}  // namespace probeloop::sim
