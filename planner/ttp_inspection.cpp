// The on-machine inspection (seed 004 L2097-L2101) of the thermal-test-piece planner
// (ttp_detail.hpp): the probe points of each feature and the probing program.
#include "planner/ttp_detail.hpp"

#include <algorithm>
#include <cmath>
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "planner/angles.hpp"

namespace probeloop::planner::ttp {

Builder::Planned Builder::planPoint(const std::string& feature, int position, int point, const ProbePoint& p) {
  const double rt = m_.probe.tip_diameter_mm / 2;
  auto toMachine = [&](const Vector3d& v, bool direction) {
    const Vector2d xy = parts::turnedByTable(v.head<2>(), p.c, cw_);
    return direction ? Vector3d(xy.x(), xy.y(), v.z()) : Vector3d(O_.x() + xy.x(), O_.y() + xy.y(), O_.z() + v.z());
  };
  const Vector3d n = toMachine(p.normal, true).normalized();
  const Vector3d contact = toMachine(p.surface + rt * p.normal, false);
  parts::ManifestPoint mp;
  mp.feature = feature;
  mp.position = position;
  mp.point = point;
  mp.contact_mm = contact;
  mp.approach = -n;
  mp.c_deg = round3(p.c);
  man_.points.push_back(mp);
  cmm_.push_back({feature, point, p.surface, p.normal});
  Planned out;
  out.contact = contact;
  const Vector3d s = contact + t_.probing.approach_mm * n, e = contact - t_.probing.overtravel_mm * n;
  out.start = Vector3d(round4(s.x()), round4(s.y()), round4(s.z()));
  out.end = Vector3d(round4(e.x()), round4(e.y()), round4(e.z()));
  out.index = static_cast<int>(man_.points.size()) - 1;
  return out;
}

void Builder::probe(const Planned& p, int position, int point, const std::string& w, bool at_start) {
  if (!at_start)
    add(gcode::ProtectedMove{p.start.x(), p.start.y(), p.start.z(), round3(t_.probing.positioning_feed_mm_per_min)},
      w + ": protected move to the start");
  OpNote n;
  n.where = w;
  n.point_index = p.index;
  n.contact_mm = p.contact;
  add(gcode::ProbeMove{p.end.x(), p.end.y(), p.end.z(), round3(t_.probing.feed_mm_per_min), position, point}, n);
  OpNote back;
  back.where = w + ": back along the approach line";
  back.retract = true;
  add(gcode::Rapid{p.start.x(), p.start.y(), p.start.z()}, back);
}

void Builder::inspection() {
  newProgram("inspection", files_.inspection, 2003,
             "probeloop thermal test piece: on-machine inspection [seed 004 L2097-L2101] - generated, do not edit");
  P().program.log_file = files_.log;
  P().program.header.push_back("probe T" + std::to_string(m_.probe.tool) + ", tip d = " +
                               formatNumber(m_.probe.tip_diameter_mm) + " mm; log: PT 1 <position> <point> x y z");
  const double rt = m_.probe.tip_diameter_mm / 2;
  const double z_cp = mz(rt + clearance_);  // tip centre: the tip's bottom `clearance` above the top
  toolChange(m_.probe.tool, "inspection: probe in");
  bool at_cp = false;
  auto clearancePlane = [&](const std::string& w) {
    add(gcode::Rapid{std::nullopt, std::nullopt, z_cp}, w + ": clearance plane");
    at_cp = true;
  };
  double c_now = 0;
  auto indexAtClearance = [&](double c, const std::string& w) {
    if (!at_cp) clearancePlane(w);
    if (std::fabs(c - c_now) > 1e-9) indexC(c, w + ": C index above the part");
    c_now = c;
  };
  // A column of points probed from one start XY (one or more heights, or one point from above).
  auto column = [&](const std::string& feature, int position, std::vector<std::pair<int, ProbePoint>> pts,
                    const std::string& w) {
    std::vector<Planned> planned;
    for (const auto& [k, p] : pts) planned.push_back(planPoint(feature, position, k, p));
    if (!at_cp) clearancePlane(w);
    add(gcode::Rapid{planned.front().start.x(), planned.front().start.y(), std::nullopt}, w + ": above the start");
    for (std::size_t i = 0; i < planned.size(); ++i)
      probe(planned[i], position, pts[i].first, w + " point " + std::to_string(pts[i].first));
    clearancePlane(w + ": up");
  };
  auto positionOf = [&](const std::string& id) { return man_.feature(id)->position; };
  auto setC = [&](const std::string& id, double c) {
    for (auto& f : man_.features)
      if (f.nominal.id == id) f.probe_c_deg = round3(c);
  };

  // TOP: 3 points per segment, inside it, away from the notches and the mark (probing -Z).
  {
    const auto q = topPoints();
    const double sx[4] = {1, -1, -1, 1}, sy[4] = {1, 1, -1, -1};
    const int pos = positionOf("TOP");
    indexAtClearance(0, "inspection TOP");
    setC("TOP", 0);
    int k = 0;
    for (int s = 0; s < 4; ++s)
      for (const auto& v : q) {
        const Vector2d p(sx[s] * v.x(), sy[s] * v.y());
        const double d_mark = pointSegment(p, t_.mark_from_mm, t_.mark_to_mm);
        if (d_mark < 2 * rt)
          throw InputError(t_.file, 0, "pre_machining.mark: the TOP point at x " + formatNumber(p.x(), 2) + " y " +
                                           formatNumber(p.y(), 2) + " lies " + formatNumber(d_mark, 2) +
                                           " mm from the mark (the inspection keeps " + formatNumber(2 * rt) + " mm away)");
        column("TOP", pos, {{++k, {Vector3d(p.x(), p.y(), 0), Vector3d::UnitZ(), 0}}}, "inspection TOP");
      }
  }
  // FLANK_P, FLANK_N: 2 heights x 4 positions along x, probing +-Y from inside the notch.
  {
    const double w2 = t_.x_notch_width_mm / 2, yn = t_.y_notch_width_mm / 2;
    const double flank_x = man_.feature("FLANK_P")->nominal.half_u_mm;
    const double xs[4] = {-(yn + 0.75 * (flank_x - yn)), -(yn + 0.25 * (flank_x - yn)), yn + 0.25 * (flank_x - yn),
                          yn + 0.75 * (flank_x - yn)};
    // Contact heights: a quarter of the depth below the top, and the tip clear of the floor.
    const double zs[2] = {t_.notchFloorZ() / 4, t_.notchFloorZ() + rt + 1.5};
    for (int s : {+1, -1}) {
      const std::string id = s > 0 ? "FLANK_P" : "FLANK_N";
      const int pos = positionOf(id);
      indexAtClearance(0, "inspection " + id);
      setC(id, 0);
      int k = 0;
      for (double x : xs) {
        std::vector<std::pair<int, ProbePoint>> pts;
        for (double z : zs) pts.push_back({++k, {Vector3d(x, s * w2, z), Vector3d(0, -s, 0), 0}});
        column(id, pos, pts, "inspection " + id);
      }
    }
  }
  // CYL: the datum band, each point indexed to face +X, probing -X; C turns with the probe
  // outside the blank.
  {
    const int pos = positionOf("CYL");
    const double rc = t_.datum_band_diameter_mm / 2, z = t_.datum_circle_z_mm;
    for (int i = 0; i < t_.datum_circle_points; ++i) {
      const double th = 360.0 * i / t_.datum_circle_points;
      const double c = cToFace(m_, th, 0);
      const Vector3d n(std::cos(degToRad(th)), std::sin(degToRad(th)), 0);
      const std::string w = "inspection CYL point " + std::to_string(i + 1);
      const Planned p = planPoint("CYL", pos, i + 1, {rc * n + Vector3d(0, 0, z), n, c});
      if (i == 0) {
        indexAtClearance(c, w);
        add(gcode::Rapid{p.start.x(), p.start.y(), std::nullopt}, w + ": above the start");
      } else {
        indexC(c, w + ": C index with the probe outside the part");
        c_now = c;
      }
      probe(p, pos, i + 1, w, i > 0);  // later points: C turned under the probe at the start
      at_cp = false;
    }
    clearancePlane("inspection CYL: up");
  }
  // Z paths: at C 0, probing -Z, entering the notch from above.
  for (int j = 1; j <= t_.z_paths; ++j) {
    const std::string id = parts::zPathId(j);
    const int pos = positionOf(id);
    indexAtClearance(0, "inspection " + id);
    setC(id, 0);
    int k = 0;
    for (double x : t_.z_path_points_along_mm)
      for (double a : t_.z_path_points_across_mm)
        column(id, pos, {{++k, {Vector3d(x, parts::zPathY(t_, j) + a, t_.cuttingZ()), Vector3d::UnitZ(), 0}}},
               "inspection " + id);
  }
  // Facets: each indexed to face +X, probing -X only (one linear axis moves, L2099).
  const FacetSide sides[4] = {FacetSide::X1, FacetSide::Y1, FacetSide::X2, FacetSide::Y2};
  for (auto s : sides)
    for (int k = 1; k <= t_.facets_per_segment; ++k) {
      const std::string id = parts::facetId(s, k);
      const int pos = positionOf(id);
      const double ang = parts::facetNormalAngle(t_, s, k), c = cToFace(m_, ang, 0);
      indexAtClearance(c, "inspection " + id);
      setC(id, c);
      const Vector3d n(std::cos(degToRad(ang)), std::sin(degToRad(ang)), 0), u(-n.y(), n.x(), 0);
      int pt = 0;
      for (double across : t_.facet_points_across_mm) {
        std::vector<std::pair<int, ProbePoint>> pts;
        for (double h : t_.facet_points_heights_mm)
          pts.push_back({++pt, {t_.facet_apothem_mm * n + across * u + Vector3d(0, 0, h), n, c}});
        column(id, pos, pts, "inspection " + id);
      }
    }
  add(gcode::RapidMachineZ{m_.tool_change.z_mm}, "end: retract to the tool-change height");
  add(gcode::RotateC{0}, "end: C back to 0");
  add(gcode::ToolChange{m_.tool_change.empty_tool, false}, "end: probe out");
}

}  // namespace probeloop::planner::ttp
