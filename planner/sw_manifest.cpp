// The stepped-workpiece planner's programs walked on the machine's clock with their checks
// (sw_detail.hpp), each step's times ('Temp state'), the plan manifest and the CMM point plan.
#include "planner/sw_detail.hpp"

#include "planner/piece_program.hpp"

#include <algorithm>
#include <cmath>
#include "core/csv.hpp"

namespace probeloop::planner::sw {

std::vector<WalkerTool> Builder::walkerTools() const {
  WalkerTool c;
  c.number = tool_->number;
  c.length_mm = tool_->length_mm;
  c.radius_mm = r_;
  c.cutter = true;
  WalkerTool p;
  p.number = m_.probe.tool;
  p.length_mm = m_.probe.length_mm;
  p.radius_mm = rt_;
  p.probe = true;
  return {c, p};
}

void Builder::walk() {
  ProgramWalker walker(m_, walkerTools());
  double offset = 0;  // the procedure's waits, machine off (not in any program)
  const double waits[3] = {0, w_.off_before_s, w_.off_after_s};
  WalkTimes total;
  for (std::size_t i = 0; i < programs_.size(); ++i) {
    auto& p = programs_[i];
    offset += waits[i];
    const auto& states = states_[i];
    const OpNote* base = p.notes.data();
    walker.setCheck([&](const Motion& mo) { check(mo, states[static_cast<std::size_t>(mo.note - base)]); });
    // A cut of several moves: from its first to its last.
    const auto [before, after] = walkProgram(walker, p, offset, CutTimes::FirstToLastOp, man_, plan_.start_s,
                                             plan_.duration_s, plan_.times, total);
    if (p.role == "finishing") {
      for (std::size_t k = 0; k < sizes_.size(); ++k) {
        SwPlannedStep s;
        s.step = static_cast<int>(k + 1);
        s.conditions = e_->steps[k];
        s.start_s = INFINITY;
        s.end_s = -INFINITY;
        for (std::size_t op = step_first_op_[k]; op <= step_last_op_[k]; ++op)
          if (p.notes[op].cut) {
            s.start_s = std::min(s.start_s, before[op]);
            s.end_s = std::max(s.end_s, after[op]);
          }
        double a = INFINITY, b = -INFINITY;
        for (const auto& c : man_.cuts)
          if (c.cycle == s.step && c.program == "finishing" && c.feature.size() > 3 && c.feature.substr(c.feature.size() - 2) != "_F" &&
              c.feature != "TOP") {
            a = std::min(a, c.start_s);
            b = std::max(b, c.end_s);
          }
        s.walls_mid_s = (a + b) / 2;
        plan_.steps.push_back(s);
      }
      for (auto& s : plan_.steps) s.temp_state_min = (s.walls_mid_s - plan_.steps.front().start_s) / 60;
    }
  }
}

void Builder::manifest() {
  auto& m = man_;
  // The piece's stylus and its stated repeatability (L769: +-2 um, read as 2 sigma).
  setManifestPiece(m, "stepped_workpiece", dialect_, programs_, plan_.start_s, plan_.duration_s, m_, rt_,
                   w_.probing.repeatability_mm * 1e3, w_.name, O_, w_.material);
  auto& s = m.sw;
  s.experiment = e_->id;
  s.transition = e_->transition;
  s.transition_feed_mm_per_min = e_->transition_feed_mm_per_min;
  s.tool_runout_mm = e_->tool_runout_mm;
  s.tool_diameter_mm = tool_->diameter_mm;
  if (comp_) {
    // As the programs apply them: rounded to 0.1 um.
    s.compensation = comp_->steps;
    for (auto& c : s.compensation) {
      for (auto& v : c.wall_um) v = toProgram(v) * 1e3;
      c.floor_um = toProgram(c.floor_um) * 1e3;
    }
    s.compensation_file = comp_->file;
  }
  s.sizes_mm = sizes_;
  for (const auto& st : plan_.steps) {
    parts::ManifestStep x;
    x.step = st.step;
    x.feed_xy_mm_per_min = st.conditions.feed_xy_mm_per_min;
    x.feed_z_mm_per_min = st.conditions.feed_z_mm_per_min;
    x.spindle_speed_rpm = st.conditions.spindle_speed_rpm;
    x.start_s = st.start_s;
    x.end_s = st.end_s;
    x.temp_state_min = st.temp_state_min;
    s.steps.push_back(x);
  }
  s.cmm = w_.cmm;
  s.cmm_plan = files_.cmm_points;
  setManifestProbingCycle(m, plan_.start_s, plan_.duration_s);  // the probing
}

std::string Builder::cmmCsv() const {
  return cmmPointsCsv({"probeloop plan: CMM points of " + w_.name + ", experiment " + e_->id +
                           " - nominal surface points and outward unit normals,",
                       "part frame at 20 C (origin at a corner of the top step in its top face, X and Y along its walls), mm"},
                      cmm_);
}

}  // namespace probeloop::planner::sw
