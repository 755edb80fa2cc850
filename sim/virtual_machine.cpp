// The virtual machine's entry points (simulateProgram, simulatePrograms, placeOnMachine) and
// its life from construction through the programs to the results; simulatePrograms turns
// the results into the outputs (logs, points CSV, truth.json, cuts, CMM). The machine's
// class and which file holds which of its jobs: sim/virtual_machine_detail.hpp.
#include "sim/virtual_machine.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <optional>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "gcode/probe_log.hpp"
#include "interop/dmis.hpp"
#include "interop/qif.hpp"
#include "sim/random_streams.hpp"
#include "sim/piece_truth.hpp"
#include "sim/virtual_machine_detail.hpp"

namespace probeloop::sim {

using Eigen::Vector3d;

namespace detail {

VirtualMachine::VirtualMachine(const parts::Machine& m, const SimulationPart& part, const MachineTruth& tr,
                               std::uint64_t seed)
    : live_(part.live), until_s_(part.until_s), m_(m), a_(part.artifact), w_(part.workpiece), tr_(tr), noise_rng_(streamSeed(seed, 1)), atc_rng_(streamSeed(seed, 2)),
      sensor_rng_(streamSeed(seed, 3)), duty_rng_(streamSeed(seed, 4)), duty_tc_rng_(streamSeed(seed, 5)),
      duty_atc_rng_(streamSeed(seed, 6)) {
  if (tr.thermal.present) {
    T0_ = tr.thermal.environment.at(0.0);
    net_ = ThermalNetwork(tr.thermal.nodes, tr.thermal.links, T0_);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    for (const auto& s : tr.thermal.sensors) sensor_offset_.push_back(s.offset_K ? *s.offset_K : u(sensor_rng_));
  }
  inputs_ << "# probeloop simulate: machine inputs sampled every " << formatNumber(tr.inputs_rate_s)
          << " s (sensors with noise and offset)\n";
  inputs_ << "time_s";
  for (const auto& s : tr.thermal.sensors) inputs_ << "," << s.column;
  inputs_ << ",c_rpm,spindle_rpm,feed_mm_per_min,mwf_on,tool_changes\n";
  if (w_) {
    stock_ = Stock(w_->stock_min_mm, w_->stock_max_mm, 0.25, w_->cylindrical);
    for (const auto& h : w_->holes) stock_.addHole(h.centre_mm, h.radius_mm, h.z_min_mm, h.z_max_mm);
  }
  if (tr.duty.tool_changes_per_hour > 0) next_duty_change_ = drawDutyGap();
  // At rest at the top of Z (the tool-change height region), X and Y at the C axis.
  pos_.xyz_mm = Vector3d(std::clamp(m_.c_axis_centre_mm.x(), m_.x.min_mm, m_.x.max_mm),
                         std::clamp(m_.c_axis_centre_mm.y(), m_.y.min_mm, m_.y.max_mm), m_.z.max_mm);
  sample();
}

// --- programs ---------------------------------------------------------------------------
// A new program on the same machine. Its interpreter starts afresh (modal state, work
// offsets); the machine keeps its clock, state, stock, tool and position. The previous
// program's M2/M30 stopped the spindle and the coolant.
void VirtualMachine::beginProgram(const std::string& file, bool fanuc) {
  if (program_index_ >= 0) {
    spindle_rpm_ = 0;
    coolant_ = false;
  }
  ++program_index_;
  program_file_ = file;
  program_fanuc_ = fanuc;
  cur_log_ = -1;
  if (fanuc)
    for (std::size_t i = 0; i < logs_.size(); ++i)
      if (logs_[i]->name == "dprnt.txt" && logs_[i]->fanuc) cur_log_ = static_cast<int>(i);
}

// A LinuxCNC log that was never named (not expected: the interpreter logs only after
// LOGOPEN) is the controller's log.
void VirtualMachine::endProgram() {
  for (auto& l : logs_)
    if (l->name.empty()) l->name = "controller.log";
}

// One program that wrote no log still has one (empty), as before.
void VirtualMachine::ensureLog(bool fanuc) {
  if (logs_.empty()) {
    program_fanuc_ = fanuc;
    if (fanuc) streamFor("dprnt.txt");
    else newStream("controller.log");
  }
}

// The machine switched off for s seconds between programs (seed 000 L992: 3 h off before
// machining and before probing): spindle, coolant (and the duty's coolant profile), axes, C
// and constant heat sources off, the structure cooling toward the hall.
void VirtualMachine::machineOff(double s) {
  spindle_rpm_ = 0;
  coolant_ = false;
  path_speed_mm_per_min_ = 0;
  const double t0 = t_;
  off_ = true;
  advance(s);
  off_ = false;
  traceRow("machine_off", pos_, 0, t0);
}

// --- results ----------------------------------------------------------------------------
std::vector<LogOutput> VirtualMachine::logs() const {
  std::vector<LogOutput> out;
  for (const auto& l : logs_) out.push_back({l->name, l->text.str()});
  return out;
}

void VirtualMachine::finish() {
  // A last sample at the end time, if the regular grid missed it.
  if (last_sample_t_ < t_ - 1e-9) sample();
}

// With several programs a last column names the program each line belongs to.
void VirtualMachine::enableTrace(bool with_program) {
  trace_on_ = true;
  trace_program_ = with_program;
  // A machine with an A axis (a table-table A/C) also traces A, before B.
  trace_ << "time_s,duration_s,line,kind,x_mm,y_mm,z_mm," << (m_.a.present ? "a_deg," : "") << "b_deg,c_deg,feed_mm_per_min,tool"
         << (with_program ? ",program" : "") << "\n";
}

}  // namespace detail

using detail::ProbeEvent;
using detail::VirtualMachine;

parts::Workpiece placeOnMachine(const parts::TestPiece& piece, const parts::Machine& machine) {
  if (const auto* t = piece.thermalTestPiece()) {
    if (!machine.c.present)
      throw InputError(machine.file, 0, "the thermal test piece is cut and indexed on a C axis, and this machine has none");
    parts::Workpiece w = *piece.stock;
    w.frame_origin_mm = parts::partOriginOnMachine(*t, machine.c_axis_centre_mm, machine.table_surface_z_mm);
    return w;
  }
  if (const auto* sw = piece.steppedWorkpiece()) {
    // The blank on its fixture on the table, the steps' centre where the planner put it.
    parts::Workpiece w = *piece.stock;
    w.frame_origin_mm = parts::steppedWorkpieceOrigin(*sw, machine);
    return w;
  }
  if (!piece.stock)
    throw InputError(piece.file, 0, "kind: " + piece.kind + " is not machined: it stands on the table as it is, not as a workpiece");
  return *piece.stock;
}

namespace {

gcode::ProgramDialect dialectOf(const std::string& program_file, const parts::Machine& machine) {
  const std::string ext = std::filesystem::path(program_file).extension().string();
  gcode::ProgramDialect dialect = machine.dialect == parts::Dialect::LinuxCnc ? gcode::ProgramDialect::LinuxCnc
                                                                              : gcode::ProgramDialect::FanucMacroB;
  if (ext == ".ngc") dialect = gcode::ProgramDialect::LinuxCnc;
  if (ext == ".nc" || ext == ".tap") dialect = gcode::ProgramDialect::FanucMacroB;
  return dialect;
}

}  // namespace

SimulationOutputs simulateProgram(const std::string& program_file, const std::string& text,
                                  const parts::Machine& machine, const SimulationPart& part,
                                  const MachineTruth& truth, std::uint64_t seed) {
  return simulatePrograms({{program_file, text, std::nullopt}}, machine, part, truth, seed);
}

SimulationOutputs simulatePrograms(const std::vector<ProgramSource>& programs, const parts::Machine& machine,
                                   const SimulationPart& given, const MachineTruth& truth, std::uint64_t seed) {
  if (programs.empty()) throw InputError("", 0, "simulate needs at least one program");
  SimulationPart part = given;
  std::optional<parts::Workpiece> placed;
  if (given.test_piece) {
    if (given.artifact || given.workpiece)
      throw InputError("", 0, "simulate needs exactly one part on the table: a test piece, or an artifact or workpiece, not both");
    if (const auto* a = given.test_piece->sphereArtifact()) {
      part.artifact = a;
    } else {
      placed = placeOnMachine(*given.test_piece, machine);
      part.workpiece = &*placed;
    }
  }
  if (part.artifact && !machine.c.present)
    throw InputError(machine.file, 0, "the sphere artifact stands on a rotary table, and this machine has no C axis");
  if (part.artifact && truth.artifact.node >= 0 && !truth.artifact.alpha_per_K)
    throw InputError(truth.file, 0, "artifact.alpha_um_per_m_K: a sphere artifact on a thermal node needs its expansion coefficient");
  if ((part.artifact != nullptr) == (part.workpiece != nullptr))
    throw InputError("", 0, "simulate needs exactly one part on the table: a sphere artifact or a workpiece");
  if (!part.cmm_points.empty() && !part.workpiece)
    throw InputError("", 0, "CMM points need a workpiece (kind: workpiece) as the part");
  const bool multi = programs.size() > 1;
  if (multi && part.trace)
    for (const auto& p : programs)
      if (std::filesystem::path(p.file).filename().string().find(',') != std::string::npos)
        throw InputError(p.file, 0, "a program file name with a comma cannot be named in trace.csv's program column");

  VirtualMachine vm(machine, part, truth, seed);
  if (part.trace) vm.enableTrace(multi);
  SimulationOutputs out;
  bool last_fanuc = false;
  std::optional<double> last_start;
  for (const auto& p : programs) {
    if (p.start_s && last_start && *p.start_s < *last_start)
      throw InputError(p.file, 0, "planned to start at " + formatNumber(*p.start_s, 1) + " s, before the program given before it (" +
                                      formatNumber(*last_start, 1) + " s): give the programs in their planned order");
    if (p.start_s) last_start = p.start_s;
    const gcode::ProgramDialect dialect = dialectOf(p.file, machine);
    last_fanuc = dialect == gcode::ProgramDialect::FanucMacroB;
    gcode::Interpreter interp(dialect, p.file, p.text);
    if (p.start_s && *p.start_s > vm.time()) vm.machineOff(*p.start_s - vm.time());
    vm.beginProgram(p.file, last_fanuc);
    const long lines_before = vm.linesStarted();
    try {
      const auto run = interp.run(vm);
      out.blocks += run.blocks_executed;
    } catch (const detail::TimeLimitReached&) {  // the campaign's end: the machine stops here
      out.blocks += vm.linesStarted() - lines_before - 1;  // the blocks before the one it stopped at
      vm.endProgram();
      break;
    }
    vm.endProgram();
  }
  vm.finish();
  if (!multi) vm.ensureLog(last_fanuc);

  out.end_time_s = vm.time();
  out.logs = vm.logs();
  if (!out.logs.empty()) {
    out.log_name = out.logs.front().name;
    out.log_text = out.logs.front().text;
  }
  out.trace_csv = vm.traceText();
  if (part.workpiece) {
    out.cuts_json = vm.cutsJson();
    if (!part.cmm_points.empty()) {
      std::vector<Eigen::Vector3d> measured;
      if (part.cmm_plan) checkCmmMoves(vm.stock(), *part.cmm_plan);
      out.cmm_csv = measureOnCmm(vm.stock(), *part.workpiece, part.cmm_points, part.cmm_points_file, seed, vm.partAlphaPerK(), 5.0,
                                 &measured);
      if (part.cmm_plan) {
        const auto results = cmmResultsDocument(*part.cmm_plan, measured);
        out.cmm_qif = interop::qifResults(results);
        out.cmm_dmo = interop::dmisOutput(results, "PROBELOOP SIMULATED CMM");
      }
    }
  }

  out.inputs_csv = vm.inputsText();
  const auto& events = vm.events();
  out.probe_events = static_cast<long>(events.size());

  // Canonical points: the logged points (as reported) joined with the event behind each.
  std::map<std::pair<int, long>, const ProbeEvent*> by_line;
  for (const auto& e : events)
    if (e.log_line > 0) by_line[{e.log_stream, e.log_line}] = &e;
  // The points CSV needs the planner's log convention ("PT cycle position point x y z").
  struct Logged {
    int stream;
    gcode::LoggedProbePoint p;
  };
  std::vector<Logged> logged;
  std::vector<std::string> not_pt;
  for (std::size_t i = 0; i < out.logs.size(); ++i) {
    try {
      for (const auto& p : gcode::parseProbeLog(out.logs[i].text, out.logs[i].name)) logged.push_back({static_cast<int>(i), p});
    } catch (const InputError&) {
      not_pt.push_back(out.logs[i].name);
    }
  }
  std::string files;
  for (const auto& p : programs) files += (files.empty() ? "" : " ") + p.file;
  // A sphere artifact's positions are spheres (S<position>); any other part's are points of
  // its features, which the evaluation maps through the plan manifest (P<position>).
  const std::string feature_prefix = part.artifact ? "S" : "P";
  std::ostringstream csv;
  csv << "# probeloop simulate " << files << ", seed " << seed << "\n";
  if (!multi && !not_pt.empty()) csv << "# the log does not follow the planner's PT convention: no points\n";
  if (multi)
    for (const auto& n : not_pt) csv << "# the log " << n << " does not follow the planner's PT convention: no points from it\n";
  csv << "time_s,cycle,c_deg,feature,point,x_mm,y_mm,z_mm,nx,ny,nz\n";
  nlohmann::ordered_json jt;
  jt["format"] = "probeloop-truth";
  jt["generator"] = "probeloop simulate";
  jt["seed"] = seed;
  jt["relative_to_cycle"] = 1;
  jt["note"] = "apparent_* = table-side location errors minus the tool-side translation plus the artifact's "
               "growth: what a sphere-artifact evaluation measures (docs/simulator.md)";
  // Quantised reports are whole resolution steps: print them as the decimals they are (6
  // for 1 um); unquantised ones at full precision (shortest round trip).
  const int decimals = truth.probe.quantise ? 6 : -1;
  std::map<int, std::pair<int, std::array<double, 7>>> per_cycle;  // cycle -> (n, sum)
  std::map<int, double> cycle_time;
  const auto& names = geometry::LocationErrors::names();
  for (const auto& [stream, p] : logged) {
    const auto it = by_line.find({stream, p.line});
    const std::string& log_name = out.logs[static_cast<std::size_t>(stream)].name;
    if (it == by_line.end())
      throw InputError(log_name, p.line, "log line without a probe event (the program logged without probing)");
    const ProbeEvent& e = *it->second;
    csv << formatNumber(e.time_s, 3) << "," << p.cycle << "," << formatNumber(e.c_deg) << "," << feature_prefix
        << p.position << "," << p.point << "," << formatNumber(e.reported_tip_mm.x(), decimals) << ","
        << formatNumber(e.reported_tip_mm.y(), decimals) << "," << formatNumber(e.reported_tip_mm.z(), decimals) << ","
        << formatNumber(e.approach.x(), 6) << "," << formatNumber(e.approach.y(), 6) << ","
        << formatNumber(e.approach.z(), 6) << "\n";
    nlohmann::ordered_json je{{"time_s", e.time_s}, {"log_line", e.log_line}};
    if (multi) je["log"] = log_name;
    je["cycle"] = p.cycle;
    je["position"] = p.position;
    je["point"] = p.point;
    je["c_deg"] = e.c_deg;
    for (int j = 0; j < 7; ++j) je[names[j]] = e.location[j];
    je["tool_um"] = {e.tool_um.x(), e.tool_um.y(), e.tool_um.z()};
    je["atc_um"] = {e.atc_um.x(), e.atc_um.y(), e.atc_um.z()};
    je["settling_um"] = e.settling_um;
    je["artifact_dT_K"] = e.artifact_dT_K;
    je["pretravel_um"] = e.pretravel_um;
    je["noise_um"] = e.noise_um;
    if (e.axes_um) je["axes_um"] = {e.axes_um->x(), e.axes_um->y(), e.axes_um->z()};
    if (e.scale_um_per_mm != Vector3d::Zero())
      je["scale_um_per_mm"] = {e.scale_um_per_mm.x(), e.scale_um_per_mm.y(), e.scale_um_per_mm.z()};
    for (int j = 0; j < 7; ++j) je[std::string("apparent_") + names[j]] = e.apparent[j];
    jt["events"].push_back(je);
    auto& acc = per_cycle[p.cycle];
    if (acc.first == 0) cycle_time[p.cycle] = e.time_s;
    ++acc.first;
    for (int j = 0; j < 7; ++j) acc.second[j] += e.apparent[j];
  }
  if (!per_cycle.empty()) {
    const auto& ref = per_cycle.begin()->second;
    for (const auto& [cyc, acc] : per_cycle) {
      nlohmann::ordered_json jc{{"cycle", cyc}, {"time_s", cycle_time[cyc]}};
      for (int j = 0; j < 7; ++j) jc[names[j]] = acc.second[j] / acc.first - ref.second[j] / ref.first;
      jt["cycles"].push_back(jc);
    }
  }
  jt["tool_changes"] = vm.toolChangeLog();
  // A machined test piece with measurement features: what a perfect CMM at 20 °C finds on
  // the surfaces as cut, and the errors the evaluation should find from them.
  if (given.test_piece && given.test_piece->thermalTestPiece() && part.workpiece) {
    const auto t = testPieceTruth(*given.test_piece, vm.stock(), vm.cutStates());
    writeTestPieceTruth(t, jt);
  } else if (given.test_piece && part.workpiece) {
    writeAsCutFeatures(asCutFeatures(*given.test_piece, vm.stock()), vm.cutStates(), jt);
  }
  out.points_csv = csv.str();
  out.truth_json = jt.dump(1) + "\n";
  return out;
}

}  // namespace probeloop::sim