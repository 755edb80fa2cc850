// The safety verifier's entry (safety.hpp): the programs run one after another on the
// checking machine (safety_checker.hpp), each probe line's other outcome tried, the findings
// sorted by program and line; the model in words; the report as text and JSON.
#include "verify/safety.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <tuple>

#include "core/error.hpp"
#include "gcode/interpreter.hpp"
#include "verify/safety_checker.hpp"

namespace probeloop::verify {
namespace {

using detail::Checker;
using detail::fmt;
using detail::Scene;
using detail::Tool;
using detail::xyz;

gcode::ProgramDialect dialectOf(const std::string& file, const parts::Machine& m) {
  const std::string ext = std::filesystem::path(file).extension().string();
  if (ext == ".ngc") return gcode::ProgramDialect::LinuxCnc;
  if (ext == ".nc" || ext == ".tap") return gcode::ProgramDialect::FanucMacroB;
  return m.dialect == parts::Dialect::LinuxCnc ? gcode::ProgramDialect::LinuxCnc : gcode::ProgramDialect::FanucMacroB;
}

// "<file>:<line>: <what>" -> line and what (a SafetyError of the interpreter).
std::pair<int, std::string> located(const std::string& file, const std::string& what) {
  const std::string pre = file + ":";
  if (what.rfind(pre, 0) != 0) return {0, what};
  std::size_t i = pre.size();
  int line = 0;
  while (i < what.size() && std::isdigit(static_cast<unsigned char>(what[i]))) line = line * 10 + (what[i++] - '0');
  if (i + 1 < what.size() && what[i] == ':') i += 2;
  return {line, what.substr(i)};
}

std::string modelText(const parts::Machine& m, const parts::TestPiece& piece, const Scene& sc, const std::map<int, Tool>& tools,
                      const Options& o, const detail::TiltAxis& tilt, double table_radius) {
  std::ostringstream s;
  const Tool& probe = tools.at(m.probe.tool);
  s << "probe T" << m.probe.tool << ": tip ball d " << fmt(2 * probe.parts[0].r, 2) << " mm, stylus shaft d "
    << fmt(2 * probe.parts[1].r, 2) << " mm x " << fmt(m.probe.stylus_length_mm, 1) << " mm, body d "
    << fmt(m.probe.body_diameter_mm, 1) << " mm up to the gauge line (" << fmt(m.probe.length_mm, 1) << " mm); ";
  for (const auto& [n, t] : tools) {
    if (t.probe) continue;
    s << "T" << n << ":";
    for (const auto& p : t.parts) s << " " << p.name << " d " << fmt(2 * p.r, 2) << " mm " << fmt(p.dz0, 1) << ".." << fmt(p.dz1, 1);
    s << " mm above the tip; ";
  }
  for (const auto& b : sc.spheres) s << b.name << " d " << fmt(2 * b.r, 2) << " mm at " << xyz(b.c) << " (C 0); ";
  for (const auto& c : sc.cyls)
    s << c.name << " d " << fmt(2 * c.r, 2) << " mm Z " << fmt(c.z0) << ".." << fmt(c.z1) << " at X" << fmt(c.c.x()) << " Y" << fmt(c.c.y()) << "; ";
  if (!sc.material.empty())
    s << sc.material_name << " of " << piece.name << " as a height field of " << fmt(o.cell_mm, 2)
      << " mm cells, cut by the programs' own feed moves with the spindle on; ";
  s << "the table at Z " << fmt(sc.table_z) << "; clearance plane " << fmt(sc.clearance) << " mm above the highest body";
  // A located tilting axis (issue 33): how its swing is checked.
  if (tilt.located) {
    const std::string q(1, tilt.name);
    s << "; the table tilts with " << q << " about the line through "
      << (tilt.name == 'B' ? "X" + fmt(tilt.point.x()) + " Z" + fmt(tilt.point.z()) + " along Y"
                           : "Y" + fmt(tilt.point.y()) + " Z" + fmt(tilt.point.z()) + " along X")
      << ": a " << q << " move (and a C move or any move on the tilted table) is checked against the bodies and the table,"
      << " a disc of radius " << fmt(table_radius, 1) << " mm (the farthest body from C plus " << fmt(detail::kTableRimMm, 0)
      << " mm) and " << fmt(detail::kTableDepthMm, 0) << " mm deep, placed by the pose; a swing keeps "
      << fmt(detail::kSwingMarginMm, 1) << " mm from them";
  }
  return s.str();
}

}  // namespace

Report checkPrograms(const std::vector<ProgramText>& programs, const parts::Machine& machine, const parts::TestPiece& piece,
                     const Options& options) {
  Report rep;
  Checker ck(machine, piece, options);
  rep.model = modelText(machine, piece, ck.scene(), ck.tools(), options, ck.tiltAxis(), ck.tableRadius());
  for (const auto& p : programs) {
    rep.programs.push_back(p.file);
    ck.file = p.file;
    const auto dialect = dialectOf(p.file, machine);
    ck.startProgram();
    bool stopped_nominal = false;
    try {
      gcode::Interpreter in(dialect, p.file, p.text);
      in.run(ck, gcode::Interpreter::kMaxBlocks, &ck);
    } catch (const SafetyError& e) {
      stopped_nominal = true;
      const auto [line, what] = located(p.file, e.what());
      ck.addAt(line, "program-stops", "the program stops here on the nominal part: " + what, ck.tip(ck.start()),
               "a program runs to its end when nothing is out of place");
    }
    // Protection: each probe line's first move with its outcome inverted must stop the program
    // before anything else happens (tried in the run, ProbeBranching above).
    for (const auto& u : ck.unprotected()) {
      // A program that stopped on its last probe move: that move's outcome was already the
      // unexpected one (its finding is program-stops).
      if (stopped_nominal && u.probe + 1 == ck.probes()) continue;
      ck.addAt(u.line, "probe-unprotected",
               u.contact ? "measuring move: when the probe does not trigger the program goes on to " + u.went_on + " instead of stopping"
                         : "positioning probe move: when the probe touches something the program goes on to " + u.went_on +
                               " instead of stopping",
               u.tip, u.contact ? "no contact -> error (G38.2, or G31 with a check and #3000)"
                                : "contact -> ABORT / #3000 (G38.3 + #5070 check, or G31 with a check)");
    }
  }
  rep.findings = ck.findings;
  std::stable_sort(rep.findings.begin(), rep.findings.end(), [&](const Finding& a, const Finding& b) {
    const auto ia = std::find(rep.programs.begin(), rep.programs.end(), a.file) - rep.programs.begin();
    const auto ib = std::find(rep.programs.begin(), rep.programs.end(), b.file) - rep.programs.begin();
    return std::tie(ia, a.line) < std::tie(ib, b.line);
  });
  return rep;
}

std::string reportText(const Report& r) {
  std::ostringstream s;
  for (const auto& f : r.findings)
    s << f.file << ":" << f.line << ": " << f.rule << ": " << f.what << ", at " << xyz(f.where_mm) << " (mm), limit: " << f.limit
      << "\n";
  return s.str();
}

std::string reportJson(const Report& r) {
  nlohmann::ordered_json j;
  j["safe"] = r.safe();
  j["programs"] = r.programs;
  j["model"] = r.model;
  j["findings"] = nlohmann::ordered_json::array();
  for (const auto& f : r.findings)
    j["findings"].push_back({{"file", f.file},
                             {"line", f.line},
                             {"rule", f.rule},
                             {"what", f.what},
                             {"where_mm", {f.where_mm.x(), f.where_mm.y(), f.where_mm.z()}},
                             {"limit", f.limit}});
  return j.dump(2) + "\n";
}

}  // namespace probeloop::verify
