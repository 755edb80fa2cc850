// The G-code interpreter, dialect LinuxCNC RS274NGC (o-words, named parameters, LOGOPEN/LOG, G38.2/G38.3), run to its end on a machine stub that answers every
// call (probe contacts alternate with misses, so both outcomes are taken).
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "fuzz/fuzz_machine.hpp"
#include "gcode/interpreter.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  const std::string text = fuzz::text(data, size);
  return fuzz::expectRefusalOrSuccess([&] {
    gcode::Interpreter interpreter(gcode::ProgramDialect::LinuxCnc, "fuzz.ngc", text);
    fuzz::FuzzMachine machine;
    interpreter.run(machine, fuzz::kMaxBlocks);
  });
}
