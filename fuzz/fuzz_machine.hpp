// A machine for the interpreter harnesses: it accepts every move, answers probe moves
// alternately with a contact halfway along the move and with no contact, knows tools 1..99,
// and keeps a clock. No physics: the harness fuzzes the interpreter, not the simulator.
//
// The property it checks (issue 28): the interpreter hands the machine only finite
// coordinates. A program that computes an infinity or a NaN must be refused (InputError) before
// a move to it; a non-finite coordinate reaching the machine aborts, which the fuzzer reports
// as a finding. The safety verifier relies on it: a NaN compares false with every limit.
#pragma once
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/error.hpp"
#include "gcode/interpreter.hpp"

namespace probeloop::fuzz {

// The interpreter's own bound is 2e7 blocks (a program that never ends); a fuzz input gets
// far fewer so that a loop costs milliseconds, not a timeout.
constexpr long kMaxBlocks = 20'000;

class FuzzMachine : public gcode::MachineInterface {
 public:
  void rapid(const gcode::MachinePosition& to) override { move(to, 10'000.0); }
  void feed(const gcode::MachinePosition& to, double feed_mm_per_min) override { move(to, feed_mm_per_min); }
  gcode::ProbeOutcome probe(const gcode::MachinePosition& to, double feed_mm_per_min,
                            gcode::ProbeMode /*mode*/) override {
    requireFinite(to);
    gcode::ProbeOutcome out;
    out.contact = (probes_++ % 2) == 0;
    out.stop = to;
    if (out.contact) {
      // 0.5 a + 0.5 b: finite for any finite a and b (a + b may overflow).
      out.stop.xyz_mm = 0.5 * at_.xyz_mm + 0.5 * to.xyz_mm;
      out.stop.a_deg = 0.5 * at_.a_deg + 0.5 * to.a_deg;
      out.stop.b_deg = 0.5 * at_.b_deg + 0.5 * to.b_deg;
      out.stop.c_deg = 0.5 * at_.c_deg + 0.5 * to.c_deg;
    }
    move(out.stop, feed_mm_per_min);
    return out;
  }
  void dwell(double seconds) override { clock_s_ += seconds; }
  void toolChange(int tool) override { tool_ = tool; clock_s_ += 5; }
  double toolLength(int tool) const override {
    if (tool < 1 || tool > 99) throw InputError("", 0, "tool " + std::to_string(tool) + " is not in the machine");
    return 100.0 + tool;
  }
  void spindle(double rpm) override { rpm_ = rpm; }
  void coolant(bool on) override { coolant_ = on; }
  void openLog(const std::string& name) override { log_open_ = true; log_name_ = name; }
  void log(const std::string& line) override { log_bytes_ += line.size(); }
  void closeLog() override { log_open_ = false; }
  double controllerClockS() const override { return clock_s_; }

 private:
  static void requireFinite(const gcode::MachinePosition& to) {
    if (to.xyz_mm.allFinite() && std::isfinite(to.a_deg) && std::isfinite(to.b_deg) && std::isfinite(to.c_deg)) return;
    std::fprintf(stderr, "fuzz machine: the interpreter handed a non-finite coordinate to the machine\n");
    std::abort();
  }
  void move(const gcode::MachinePosition& to, double feed_mm_per_min) {
    requireFinite(to);
    const double d = (to.xyz_mm - at_.xyz_mm).norm();
    if (std::isfinite(d) && feed_mm_per_min > 0) clock_s_ += 60.0 * d / feed_mm_per_min;
    at_ = to;
  }
  gcode::MachinePosition at_;
  long probes_ = 0;
  double clock_s_ = 0, rpm_ = 0;
  int tool_ = 0;
  bool coolant_ = false, log_open_ = false;
  unsigned long log_bytes_ = 0;
  std::string log_name_;
};

}  // namespace probeloop::fuzz
