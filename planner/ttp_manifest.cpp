// The thermal-test-piece planner's programs walked on the machine's clock with the collision
// rules (ttp_detail.hpp), then the plan manifest and the CMM point plan.
#include "planner/ttp_detail.hpp"

#include "planner/piece_program.hpp"

#include <algorithm>
#include <cmath>
#include "core/csv.hpp"

namespace probeloop::planner::ttp {

std::vector<WalkerTool> walkerTools(const ThermalTestPiece& t) {
  std::vector<WalkerTool> tools;
  for (const auto& c : t.tools) {
    WalkerTool w;
    w.number = c.number;
    w.length_mm = c.length_mm;
    w.radius_mm = c.diameter_mm / 2;
    w.cutter = true;
    tools.push_back(w);
  }
  return tools;
}

void Builder::walk() {
  ProgramWalker walker(m_, walkerTools(t_));
  const Collisions col{env_, O_, cw_};
  for (std::size_t i = 0; i < programs_.size(); ++i) {
    auto& p = programs_[i];
    const bool finished = p.role != "pre_machining";
    walker.setCheck([&col, finished](const Motion& mo) { col.check(mo, finished); });
    // The programs run back to back: no waits between them (an offset of 0 s).
    const auto [before, after] = walkProgram(walker, p, 0.0, CutTimes::LastOp, man_, plan_.start_s, plan_.duration_s,
                                             plan_.times, total_);
    if (p.role == "test") {
      for (std::size_t c = 0; c < man_.cut_cycles.size(); ++c) {
        man_.cut_cycles[c].start_s = before[cycle_first_op_[c]];
        man_.cut_cycles[c].end_s = after[cycle_last_op_[c]];
        const double d = man_.cut_cycles[c].end_s - man_.cut_cycles[c].start_s;
        plan_.cycle_s_min = c == 0 ? d : std::min(plan_.cycle_s_min, d);
        plan_.cycle_s_max = c == 0 ? d : std::max(plan_.cycle_s_max, d);
      }
    }
  }
}

void Builder::manifest() {
  auto& m = man_;
  setManifestPiece(m, "thermal_test_piece", dialect_, programs_, plan_.start_s, plan_.duration_s, m_,
                   m_.probe.tip_diameter_mm / 2, m_.probe.repeatability_2sigma_um, t_.name, O_, t_.material);
  m.evaluation = evaluation_;
  auto& c = m.ttp;
  c.z_paths = t_.z_paths;
  c.facets_per_segment = t_.facets_per_segment;
  c.eq_7_10_alpha_um_per_m_K = t_.eq_7_10_alpha_um_per_m_K;
  c.alpha_u_um_per_m_K = t_.alpha_u_um_per_m_K;
  c.eq_7_10_radius_mm = t_.eq_7_10_radius_mm;
  c.cmm = t_.cmm;
  c.on_machine_repeatability_um = t_.on_machine_repeatability_um;
  c.on_machine_temperature_change_K = t_.on_machine_temperature_change_K;
  c.cmm_plan = files_.cmm_points;
  setManifestProbingCycle(m, plan_.start_s, plan_.duration_s);  // the inspection
}

std::string Builder::cmmCsv() const {
  return cmmPointsCsv({"probeloop plan: CMM points of " + t_.name + " - nominal surface points and outward unit normals,",
                       "part frame at 20 C (origin on the C axis in the finished top face, X along the large notch), mm"},
                      cmm_);
}

}  // namespace probeloop::planner::ttp
