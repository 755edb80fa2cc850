#include "planner/piece_program.hpp"

#include <cmath>

#include "core/csv.hpp"
#include "planner/piece_manifest.hpp"

namespace probeloop::planner {

std::string programExtension(parts::Dialect d) { return d == parts::Dialect::LinuxCnc ? ".ngc" : ".nc"; }

std::string programText(const NotedProgram& p, parts::Dialect dialect) {
  return dialect == parts::Dialect::LinuxCnc ? gcode::writeLinuxCnc(p.program) : gcode::writeFanucMacroB(p.program);
}

OpNote opNote(const std::string& where, bool cut, int cut_index) {
  OpNote n;
  n.where = where;
  n.cut = cut;
  n.cut_index = cut_index;
  return n;
}

std::vector<std::string> programHeader(const parts::Machine& m, const std::string& part) {
  return {
      "machine: " + m.name,
      part,
      "coordinates: G" + std::to_string(53 + m.work_offset) + " zeroed = machine coordinates of the tool tip with G43",
  };
}

std::string toolLine(int number, const parts::CuttingTool& tool) {
  return "T" + std::to_string(number) + ": " + (tool.name.empty() ? tool.kind : tool.name) + ", d = " +
         formatNumber(tool.diameter_mm) + " mm, length " + formatNumber(tool.length_mm) + " mm";
}

WalkedOps walkProgram(ProgramWalker& walker, const NotedProgram& p, double offset_s, CutTimes cuts,
                      parts::PlanManifest& man, std::vector<double>& start_s, std::vector<double>& duration_s,
                      std::vector<WalkTimes>& times, WalkTimes& total) {
  const double t0 = walker.time();
  WalkedOps w{std::vector<double>(p.program.ops.size(), NAN), std::vector<double>(p.program.ops.size(), NAN)};
  walker.run(p, [&](std::size_t op, double a, double b) {
    w.before[op] = a + offset_s;
    w.after[op] = b + offset_s;
    const auto& n = p.notes[op];
    if (n.cut_index >= 0) {
      auto& c = man.cuts[static_cast<std::size_t>(n.cut_index)];
      if (cuts == CutTimes::LastOp || std::isnan(c.start_s)) c.start_s = a + offset_s;
      c.end_s = b + offset_s;
    }
    if (n.point_index >= 0) man.points[static_cast<std::size_t>(n.point_index)].time_in_cycle_s = b - t0;
  });
  start_s.push_back(t0 + offset_s);
  duration_s.push_back(walker.time() - t0);
  times.push_back(walker.times() - total);
  total = walker.times();
  return w;
}

}  // namespace probeloop::planner
