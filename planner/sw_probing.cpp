// On-machine probing (seed 000 Sec. 3.4, L1040) of the stepped-workpiece planner
// (sw_detail.hpp): the probe points and the probing program, paths kept clear of the material.
#include "planner/sw_detail.hpp"

#include <algorithm>
#include <cmath>
#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::planner::sw {

Builder::Planned Builder::planPoint(const parts::SwProbePoint& p, int position, int point, bool cmm) {
  const Vector3d n = p.normal;
  const Vector3d contact = O_ + p.contact_mm + rt_ * n;
  parts::ManifestPoint mp;
  mp.feature = p.feature;
  mp.position = position;
  mp.point = point;
  mp.contact_mm = contact;
  mp.approach = -n;
  man_.points.push_back(mp);
  if (cmm) cmm_.push_back({p.feature, point, p.contact_mm, n});
  const Vector3d s = contact + w_.probing.approach_mm * n, e = contact - w_.probing.overtravel_mm * n;
  return {Vector3d(round4(s.x()), round4(s.y()), round4(s.z())), Vector3d(round4(e.x()), round4(e.y()), round4(e.z())), contact,
          static_cast<int>(man_.points.size()) - 1};
}

void Builder::probing() {
  newProgram("probing", files_.probing, 3003,
             "probeloop stepped workpiece: on-machine probing [seed 000 Sec. 3.4, L1040] - generated, do not edit");
  P().program.log_file = files_.log;
  P().program.header.push_back("probe T" + std::to_string(m_.probe.tool) + " with the piece's stylus, ball d = " +
                               formatNumber(w_.probing.tip_diameter_mm) + " mm; log: PT 1 <position> <point> x y z");
  toolChange(m_.probe.tool, "probing: probe in");
  const double z_cp = mz(rt_ + w_.machining.clearance_mm);  // the ball's bottom `clearance` above the top
  const double Fp = round3(w_.probing.positioning_feed_mm_per_min), Fm = round3(w_.probing.feed_mm_per_min);
  const auto pts = parts::probePoints(w_, features_);
  auto positionOf = [&](const std::string& id) { return man_.feature(id)->position; };
  auto probeFeature = [&](const std::string& id, const std::vector<const parts::SwProbePoint*>& list, int first_point, bool cmm,
                          const std::string& w) {
    add(gcode::Rapid{std::nullopt, std::nullopt, z_cp}, w + ": clearance plane");
    bool first = true;
    int k = first_point;
    Vector3d prev = Vector3d::Zero();
    for (const auto* p : list) {
      const Planned q = planPoint(*p, positionOf(id), k, cmm);
      const std::string wp = w + " point " + std::to_string(k);
      // From one start to the next straight when the stylus passes clear of the part (a
      // floor's points go round a corner of the step: over it, by the clearance plane).
      if (!first && !pathClear(prev, q.start, rt_)) {
        add(gcode::Rapid{std::nullopt, std::nullopt, z_cp}, wp + ": up to the clearance plane");
        first = true;
      }
      if (first) add(gcode::Rapid{q.start.x(), q.start.y(), std::nullopt}, wp + ": above the start");
      first = false;
      prev = q.start;
      add(gcode::ProtectedMove{q.start.x(), q.start.y(), q.start.z(), Fp}, wp + ": protected move to the start");
      OpNote n;
      n.where = wp;
      n.point_index = q.index;
      n.contact_mm = q.contact;
      add(gcode::ProbeMove{q.end.x(), q.end.y(), q.end.z(), Fm, positionOf(id), k}, n);
      OpNote back;
      back.where = wp + ": back along the approach line";
      back.retract = true;
      add(gcode::Rapid{q.start.x(), q.start.y(), q.start.z()}, back);
      ++k;
    }
    add(gcode::Rapid{std::nullopt, std::nullopt, z_cp}, w + ": up to the clearance plane");
  };
  for (const auto& f : features_) {
    std::vector<const parts::SwProbePoint*> list;
    for (const auto& p : pts)
      if (p.feature == f.id) list.push_back(&p);
    probeFeature(f.id, list, 1, true, "probing " + f.id);
  }
  // The repeatability check (L769): step 3's wall points again, numbered on.
  for (int pass = 2; pass <= w_.probing.step3_wall_passes; ++pass)
    for (const auto& f : features_) {
      if (f.role != "wall" || f.index != 3) continue;
      std::vector<const parts::SwProbePoint*> list;
      for (const auto& p : pts)
        if (p.feature == f.id) list.push_back(&p);
      probeFeature(f.id, list, static_cast<int>(list.size()) * (pass - 1) + 1, false,
                   "probing " + f.id + " repeat " + std::to_string(pass - 1));
    }
  add(gcode::RapidMachineZ{m_.tool_change.z_mm}, "end: retract to the tool-change height");
  add(gcode::ToolChange{m_.tool_change.empty_tool, false}, "end: probe out");
}

bool Builder::pathClear(const Vector3d& a, const Vector3d& b, double rho) const {
  const Vector3d off = O_ + Vector3d(c_, c_, 0);
  const auto boxes = material_.boxes();
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.25)));
  for (int i = 0; i <= n; ++i) {
    const Vector3d q = a - off + (b - a) * (static_cast<double>(i) / n);
    for (const auto& x : boxes)
      if (q.z() - rho < x.z_hi - 1e-6 && rectDistance(q.head<2>(), x.hx, x.hy) < rho + 0.5) return false;
  }
  return true;
}

}  // namespace probeloop::planner::sw
