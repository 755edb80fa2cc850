#include "planner/piece_plan.hpp"

#include "planner/cmm_plan.hpp"

#include <cstdio>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include "core/paths.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "planner/sphere_cycle.hpp"
#include "planner/stepped_workpiece.hpp"
#include "planner/thermal_test_piece.hpp"

namespace probeloop::planner {

namespace {

std::string printf1(const char* fmt, double v) {
  char b[128];
  std::snprintf(b, sizeof b, fmt, v);
  return b;
}

std::string hms(double s) {
  const long t = std::lround(s);
  char b[32];
  std::snprintf(b, sizeof b, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  return b;
}

TestPiecePlan sphere(const parts::SphereArtifact& a, const parts::Machine& m, parts::Dialect dialect,
                     const std::string& out_dir) {
  PlanFiles files;
  const bool linux = dialect == parts::Dialect::LinuxCnc;
  files.program_file = linux ? "sphere_cycle.ngc" : "sphere_cycle.nc";
  auto plan = planSphereCycle(a, m, files);
  plan.manifest.dialect = parts::dialectName(dialect);
  plan.manifest.programs.front().dialect = plan.manifest.dialect;
  TestPiecePlan out;
  PlannedProgram p;
  p.role = "sphere_cycle";
  p.file = files.program_file;
  p.text = programText(plan, dialect);
  const double T = plan.cycle_time.total();
  p.duration_s = plan.manifest.cycles * T + (plan.manifest.cycles - 1) * plan.manifest.gap_s;
  out.programs.push_back(p);
  out.files.emplace_back(kQifProbePlanFile, qifSphereProbePlan(plan.manifest));
  // The planner part of `probeloop plan`'s report (unchanged since the sphere cycle came).
  std::ostringstream s;
  const auto& t = plan.cycle_time;
  char line[256];
  std::snprintf(line, sizeof line, "Planned %d cycles of the sphere cycle for %s (%s dialect)\n", plan.manifest.cycles,
                m.name.c_str(), parts::dialectName(dialect));
  s << line;
  s << "  wrote " << pathIn(out_dir, files.program_file) << " and " << pathIn(out_dir, "plan.json") << "\n";
  s << printf1("Estimated cycle time %.1f s (seed 004: 95 s incl. two tool changes):\n", t.total());
  s << printf1("  tool changes %6.1f s\n", t.tool_change_s) << printf1("  C indexing   %6.1f s\n", t.c_index_s)
    << printf1("  rapids       %6.1f s\n", t.rapid_s) << printf1("  protected    %6.1f s\n", t.protected_s)
    << printf1("  probing      %6.1f s\n", t.probing_s);
  s << "  (no acceleration; see docs/sphere-cycle.md for the comparison with 95 s)\n";
  s << "  the probing plan as QIF 3.0: " << pathIn(out_dir, kQifProbePlanFile) << "\n";
  if (a.live_interval)
    s << "  interval between cycles: live, read from "
      << (linux ? "HAL analog input " + std::to_string(gcode::kLiveIntervalLinuxCncInput) + " (M66)"
                : "#" + std::to_string(gcode::kLiveIntervalFanucVariable) + " (FOCAS cnc_wrmacro)")
      << "; 0 runs the cycles back to back; plan.json's schedule is nominal (gap " << formatNumber(a.gap_s) << " s)\n";
  out.summary = s.str();
  out.manifest = std::move(plan.manifest);
  return out;
}

// One program's time by kind of op, as the summary prints it (kinds under 0.05 s left out).
std::string timesLine(const WalkTimes& w) {
  const std::pair<const char*, double> kinds[] = {
      {"feeds", w.feed_s},         {"C turned by feed", w.rotary_feed_s}, {"rapids", w.rapid_s},
      {"indexing", w.rotary_index_s}, {"tool changes", w.tool_change_s},  {"protected moves", w.protected_s},
      {"probing", w.probing_s},    {"dwells", w.dwell_s}};
  std::string out, sep = "    ";
  for (const auto& [name, v] : kinds)
    if (v > 0.05) {
      out += sep + name + " " + formatNumber(v, 1) + " s";
      sep = ", ";
    }
  return out + "\n";
}

// The planned programs of a machined test piece as `plan` writes them: text in the dialect,
// start and duration on the planned clock.
std::vector<PlannedProgram> plannedPrograms(const std::vector<NotedProgram>& programs, const std::vector<double>& start_s,
                                            const std::vector<double>& duration_s, parts::Dialect dialect) {
  std::vector<PlannedProgram> out;
  for (std::size_t i = 0; i < programs.size(); ++i) {
    PlannedProgram p;
    p.role = programs[i].role;
    p.file = programs[i].file;
    p.text = dialect == parts::Dialect::LinuxCnc ? gcode::writeLinuxCnc(programs[i].program)
                                                 : gcode::writeFanucMacroB(programs[i].program);
    p.start_s = start_s[i];
    p.duration_s = duration_s[i];
    out.push_back(p);
  }
  return out;
}

TestPiecePlan thermal(const parts::TestPiece& piece, const parts::ThermalTestPiece& t, const parts::Machine& m,
                      parts::Dialect dialect, const std::string& out_dir) {
  // The features and evaluation rules of the loaded test piece, as the manifest carries them.
  auto plan = planThermalTestPiece(t, piece.features, piece.evaluation, m, dialect);
  TestPiecePlan out;
  out.programs = plannedPrograms(plan.programs, plan.start_s, plan.duration_s, dialect);
  const auto& man = plan.manifest;
  out.files.emplace_back(man.ttp.cmm_plan, plan.cmm_points_csv);
  out.files.emplace_back(kQifCmmPlanFile, qifCmmPlan(man, plan.cmm_points_csv));
  out.files.emplace_back(kDmisCmmPlanFile, dmisCmmPlan(man, plan.cmm_points_csv));

  std::ostringstream s;
  s << "Planned the thermal test piece (seed 004 Ch. 7) for " << m.name << " (" << parts::dialectName(dialect)
    << " dialect): three programs, run back to back\n";
  const char* notes[3] = {"seed 004: about 15 min, L2018", t.wait_s == 3600 ? "seed 004: 8 h 5 min, L2043" : "", ""};
  for (std::size_t i = 0; i < out.programs.size(); ++i) {
    const auto& p = out.programs[i];
    s << "  " << p.file << std::string(p.file.size() < 18 ? 18 - p.file.size() : 1, ' ')
      << (dialect == parts::Dialect::FanucMacroB ? "O" + std::to_string(plan.programs[i].program.number) + "  " : std::string())
      << "starts "
      << hms(p.start_s) << ", runs " << hms(p.duration_s) << " (" << formatNumber(p.duration_s, 1) << " s)";
    if (i == 1) {
      s << ": " << plan.loads.size() << " waits of " << formatNumber(t.wait_s) << " s + " << man.cut_cycles.size()
        << " cutting cycles of " << formatNumber(plan.cycle_s_min, 1) << "-" << formatNumber(plan.cycle_s_max, 1) << " s";
    }
    if (i == 2) s << ": " << man.points.size() << " probed points, log " << plan.programs[i].program.log_file;
    if (notes[i][0]) s << " (" << notes[i] << ")";
    s << "\n";
    s << timesLine(plan.times[i]);
  }
  const int surfaces = t.z_paths + 4 * t.facets_per_segment;
  s << surfaces << " measurement surfaces: " << t.z_paths << " Z paths (" << formatNumber(t.z_path_pitch_mm) << " mm pitch) + "
    << 4 * t.facets_per_segment << " facets (4 x " << t.facets_per_segment << ", " << formatNumber(t.facet_pitch_deg)
    << " deg pitch), " << formatNumber(t.cut_depth_mm) << " mm deep; cycle 0 cuts the references (Z path " << t.order.front()
    << ", facets " << t.order.front() << ")\n";
  for (const auto& ph : t.load) {
    s << "Load " << ph.name << ": " << ph.cycles << " x " << formatNumber(t.wait_s) << " s";
    const TtpLoad* l = nullptr;
    for (const auto& x : plan.loads)
      if (x.phase == ph.name) l = &x;
    if (l && l->rpm > 0) {
      s << ", C at " << formatNumber(l->rpm) << " rpm (" << l->pairs << " x " << l->turns_per_move
        << " turns forward and back"
        << (l->dwell_s > 0 ? ", then " + formatNumber(l->dwell_s, 3) + " s dwell" : std::string()) << ")";
      if (l->rpm < l->requested_rpm)
        s << " - " << formatNumber(l->requested_rpm) << " rpm asked, capped at C's max_turning_speed of " << m.file;
    } else {
      s << ", NC hold at C 0 (dwell)";
    }
    s << "\n";
  }
  s << "Test: Z set once, tool tip at Z " << formatNumber(plan.test_cutting_z_mm, 4) << " (part z " << formatNumber(t.cuttingZ())
    << ") from the first cut to the last\n";
  std::map<std::string, int> per;
  for (const auto& p : man.points) ++per[p.feature];
  s << "Inspection: " << man.points.size() << " points (TOP " << per["TOP"] << ", FLANK_P " << per["FLANK_P"] << ", FLANK_N "
    << per["FLANK_N"] << ", CYL " << per["CYL"] << ", " << t.z_paths << " Z paths x " << per[parts::zPathId(1)] << ", "
    << 4 * t.facets_per_segment << " facets x " << per[parts::facetId(parts::FacetSide::X1, 1)]
    << "); the CMM measures the same points (" << man.ttp.cmm_plan << ", as QIF 3.0 " << kQifCmmPlanFile << ", as DMIS "
    << kDmisCmmPlanFile << ")\n";
  s << "  wrote";
  for (const auto& p : out.programs) s << " " << pathIn(out_dir, p.file) << ",";
  s << " " << pathIn(out_dir, man.ttp.cmm_plan) << ", " << pathIn(out_dir, kQifCmmPlanFile) << ", " << pathIn(out_dir, kDmisCmmPlanFile) << " and "
    << pathIn(out_dir, "plan.json") << "\n";
  s << "  (planned with the simulator's clock, no acceleration: docs/simulator.md §2, docs/thermal-test-piece.md §5)\n";
  out.summary = s.str();
  out.manifest = std::move(plan.manifest);
  return out;
}

std::string hm(double s) {
  const long t = std::lround(s);
  char b[32];
  std::snprintf(b, sizeof b, "%ld:%02ld", t / 3600, (t / 60) % 60);
  return b;
}

TestPiecePlan stepped(const parts::SteppedWorkpiece& w, const std::string& experiment, const parts::Machine& m,
                      parts::Dialect dialect, const std::string& out_dir, const parts::SwCompensation* comp) {
  if (experiment.empty()) {
    std::string ids;
    for (const auto& e : w.experiments) ids += (ids.empty() ? "" : ", ") + e.id;
    throw InputError(w.file, 0, "kind: stepped_workpiece: choose the experiment to plan with --experiment (one of " + ids + ")");
  }
  auto plan = planSteppedWorkpiece(w, experiment, m, dialect, comp);
  TestPiecePlan out;
  out.programs = plannedPrograms(plan.programs, plan.start_s, plan.duration_s, dialect);
  const auto& man = plan.manifest;
  out.files.emplace_back(man.sw.cmm_plan, plan.cmm_points_csv);
  out.files.emplace_back(kQifCmmPlanFile, qifCmmPlan(man, plan.cmm_points_csv));
  out.files.emplace_back(kDmisCmmPlanFile, dmisCmmPlan(man, plan.cmm_points_csv));
  const auto* e = w.experiment(experiment);
  std::ostringstream s;
  std::string sizes;
  for (double v : plan.sizes_mm) sizes += (sizes.empty() ? "" : "/") + formatNumber(v);
  s << "Planned experiment " << e->id << " on the stepped workpiece (seed 000 Table 4.1) for " << m.name << " ("
    << parts::dialectName(dialect) << " dialect): steps " << sizes << " mm, transition " << e->transition;
  if (e->transition != "continuous") s << " at " << formatNumber(e->transition_feed_mm_per_min) << " mm/min";
  s << "\n";
  const char* waits[3] = {"", " after the machine is off for ", " after the cool-down of "};
  const double wait_s[3] = {0, w.off_before_s, w.off_after_s};
  for (std::size_t i = 0; i < out.programs.size(); ++i) {
    const auto& p = out.programs[i];
    s << "  " << p.file << std::string(p.file.size() < 14 ? 14 - p.file.size() : 1, ' ')
      << (dialect == parts::Dialect::FanucMacroB ? "O" + std::to_string(plan.programs[i].program.number) + "  " : std::string())
      << "starts " << hms(p.start_s) << waits[i] << (i ? hm(wait_s[i]) : std::string()) << ", runs " << hms(p.duration_s)
      << " (" << formatNumber(p.duration_s, 1) << " s)";
    if (p.role == "probing") s << ": " << man.points.size() << " probed points, log " << plan.programs[i].program.log_file;
    s << "\n";
    s << timesLine(plan.times[i]);
  }
  if (comp) {
    s << "Compensated (" << comp->file << "): walls moved in by XP/XN/YP/YN, floors raised by, um:\n";
    for (const auto& c : comp->steps)
      s << "  step " << c.step << ": " << formatNumber(c.wall_um[0], 2) << " / " << formatNumber(c.wall_um[1], 2) << " / "
        << formatNumber(c.wall_um[2], 2) << " / " << formatNumber(c.wall_um[3], 2) << ", floor " << formatNumber(c.floor_um, 2) << "\n";
  }
  s << "Steps (Temp state T = mid-time of the step's wall cuts from the start of step 1, min):\n";
  for (const auto& st : plan.steps)
    s << "  step " << st.step << ": feed XY " << formatNumber(st.conditions.feed_xy_mm_per_min) << " / Z "
      << formatNumber(st.conditions.feed_z_mm_per_min) << " mm/min, " << formatNumber(st.conditions.spindle_speed_rpm)
      << " rpm, cut " << hms(st.start_s) << " - " << hms(st.end_s) << ", T = " << formatNumber(st.temp_state_min, 2) << " min\n";
  s << "  wrote";
  for (const auto& p : out.programs) s << " " << pathIn(out_dir, p.file) << ",";
  s << " " << pathIn(out_dir, man.sw.cmm_plan) << ", " << pathIn(out_dir, kQifCmmPlanFile) << ", " << pathIn(out_dir, kDmisCmmPlanFile) << " and "
    << pathIn(out_dir, "plan.json") << "\n";
  s << "  (planned with the simulator's clock, no acceleration: docs/simulator.md §2, docs/stepped-workpiece.md §4)\n";
  out.summary = s.str();
  out.manifest = std::move(plan.manifest);
  return out;
}

}  // namespace

TestPiecePlan planTestPiece(const parts::TestPiece& piece, const parts::Machine& machine, parts::Dialect dialect,
                            const std::string& out_dir, const std::string& experiment,
                            const parts::SwCompensation* compensation) {
  if (const auto* w = piece.steppedWorkpiece()) return stepped(*w, experiment, machine, dialect, out_dir, compensation);
  if (compensation)
    throw InputError(compensation->file, 0, "--compensate: only a stepped workpiece's finishing takes a compensation (this is kind: " +
                                                piece.kind + ")");
  if (!experiment.empty())
    throw InputError(piece.file, 0, "--experiment " + experiment + ": only a stepped workpiece has experiments (this is kind: " +
                                        piece.kind + ")");
  if (const auto* a = piece.sphereArtifact()) return sphere(*a, machine, dialect, out_dir);
  if (const auto* t = piece.thermalTestPiece()) return thermal(piece, *t, machine, dialect, out_dir);
  if (std::holds_alternative<parts::Workpiece>(piece.description))
    throw InputError(piece.file, 0,
                     "a plain workpiece has no planner: write its program yourself and run it with probeloop simulate");
  throw InputError(piece.file, 0, "kind: '" + piece.kind + "' has no planner");
}

}  // namespace probeloop::planner
