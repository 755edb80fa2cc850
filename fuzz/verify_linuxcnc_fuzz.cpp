// The safety verifier (verify/safety.hpp) on LinuxCNC programs, against the LinuxCNC mill and
// the sphere artifact shipped in parts/. Its property (issue 28): a program the verifier calls
// safe has only finite coordinates. A verdict of "safe" is followed by a run of the same
// program on the fuzz machine, which aborts on any non-finite coordinate; a refusal
// (InputError) or findings are the contract.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "fuzz/fuzz_machine.hpp"
#include "fuzz/fuzz_support.hpp"
#include "gcode/interpreter.hpp"
#include "parts/machine.hpp"
#include "parts/piece_kinds.hpp"
#include "verify/safety.hpp"

namespace {

// The shipped machine and artifact (fuzz/fixtures/../../parts/), loaded once.
struct Scene {
  probeloop::parts::Machine machine;
  probeloop::parts::TestPiece piece;
};
const Scene& scene() {
  static const Scene s = [] {
    const std::string parts = std::string(PROBELOOP_FUZZ_FIXTURES) + "/../../parts/";
    try {
      return Scene{probeloop::parts::loadMachine(parts + "machines/linuxcnc_rotary_mill.yaml"),
                   probeloop::parts::loadTestPiece(parts + "sphere_artifact.yaml")};
    } catch (const std::exception& e) {
      std::fprintf(stderr, "fuzz harness: %s\n", e.what());
      std::abort();
    }
  }();
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  const std::string text = fuzz::text(data, size);
  bool safe = false;
  fuzz::expectRefusalOrSuccess([&] {
    safe = verify::checkPrograms({{"fuzz.ngc", text}}, scene().machine, scene().piece).safe();
  });
  if (safe) {
    gcode::Interpreter interpreter(gcode::ProgramDialect::LinuxCnc, "fuzz.ngc", text);
    fuzz::FuzzMachine machine;  // aborts on a non-finite coordinate
    fuzz::expectRefusalOrSuccess([&] { interpreter.run(machine, fuzz::kMaxBlocks); });
  }
  return 0;
}
