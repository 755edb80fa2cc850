// Independent random streams per effect, so switching one effect on does not reshuffle the
// draws of another (splitmix64 of seed and stream number). Streams in use: 1 probe noise,
// 2 ATC steps, 3 sensors, 4 duty C levels, 5 duty tool-change times, 6 duty ATC steps,
// 7 the part's temperature in the CMM room. The CMM's own noise keeps its older stream
// (seed ^ constant, sim/cmm_stage.cpp) so its draws stay what they were.
#pragma once
#include <cstdint>

namespace probeloop::sim {

inline std::uint64_t streamSeed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ULL + stream * 0xBF58476D1CE4E5B9ULL + 0x94D049BB133111EBULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace probeloop::sim
