// The thermal test piece's on-machine measurements against its plan: a Fanuc DPRNT file
// (dprnt.txt), a LinuxCNC log, or the simulator's points CSV, each read by the format that
// detectTtpFormat names and by the two log formats forced.
#include <cstddef>
#include <cstdint>

#include "evaluate/ttp_ingest.hpp"
#include "fuzz/fixtures.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  const auto& manifest = fuzz::ttpManifest();
  const std::string text = fuzz::text(data, size);
  fuzz::expectRefusalOrSuccess([&] {
    const std::string format = evaluate::detectTtpFormat("dprnt.txt", text);
    if (format != "cmm" && format != "gauge") evaluate::readTtpOnMachine("dprnt.txt", text, format, manifest);
  });
  fuzz::expectRefusalOrSuccess([&] { evaluate::readTtpOnMachine("dprnt.txt", text, "fanuc", manifest); });
  return fuzz::expectRefusalOrSuccess([&] { evaluate::readTtpOnMachine("probe.log", text, "linuxcnc", manifest); });
}
