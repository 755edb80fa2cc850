// The simulator's truths: machine_truth (geometric, thermal network, probe, spindle, forces) and rigid_location_truth YAML. Both readers see every input.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "sim/machine_truth.hpp"
#include "sim/rigid_campaign.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".yaml");
  const std::string& path = file.write(data, size);
  fuzz::expectRefusalOrSuccess([&] { sim::loadMachineTruth(path); });
  return fuzz::expectRefusalOrSuccess([&] { sim::loadRigidTruth(path); });
}
