// The G-code interpreter, dialect Fanuc macro B (WHILE/DO/END, IF..GOTO, #3000 alarms, POPEN/DPRNT/PCLOS, G31), run to its end on a machine stub that answers every
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
    gcode::Interpreter interpreter(gcode::ProgramDialect::FanucMacroB, "fuzz.nc", text);
    fuzz::FuzzMachine machine;
    interpreter.run(machine, fuzz::kMaxBlocks);
  });
}
