// Pre-machining (seed 004 L2002-L2018) and the test with its C load (L2022-L2047,
// docs/thermal-test-piece.md §2) of the thermal-test-piece planner (ttp_detail.hpp).
#include "planner/ttp_detail.hpp"

#include <algorithm>
#include <cmath>
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "planner/angles.hpp"

namespace probeloop::planner::ttp {

void Builder::preMachining() {
  newProgram("pre_machining", files_.pre_machining, 2001,
             "probeloop thermal test piece: pre-machining [seed 004 L2002-L2018] - generated, do not edit");
  toolHeader({t_.band_tool, t_.face_tool, t_.mark_tool, t_.y_notch_tool, t_.x_notch_tool, t_.facet_pre_tool});
  const bool wet = t_.pre_machining_coolant;
  const double zc = env_.blank_top + clearance_;

  // Step 1: the bands by turning C only, the tool standing on the machine's +X side of C at
  // Y0 (L2006: "at X0 or Y0"); bottom band first, so that each band leaves the one below.
  add(gcode::Comment{"step 1: bands by turning C only, bottom first [L2006]"}, "bands");
  cutterFor(t_.band_tool, "bands");
  const double rb = radius(t_.band_tool), x_out = env_.R + rb + kOutside;
  rapidXY(x_out, 0, "bands: beside the blank on +X");
  auto bands = t_.bands;
  std::stable_sort(bands.begin(), bands.end(), [](const auto& a, const auto& b) { return a.z_from_mm < b.z_from_mm; });
  for (const auto& b : bands) {
    const std::string w = "band d" + formatNumber(b.diameter_mm);
    rapidZ(b.z_from_mm, w + ": down outside the blank");
    const double x_cut = b.diameter_mm / 2 + rb;
    feedXY(x_cut, 0, t_.band_feed_mm_per_min, w + ": feed radially in", true);
    // One turn of C: the edge at radius d/2 moves at the band feed.
    const double F = round3(t_.band_feed_mm_per_min * 360.0 / (kPi * b.diameter_mm));
    const bool datum = std::fabs(b.diameter_mm - t_.datum_band_diameter_mm) < 1e-9;
    int ci = -1;
    if (datum) ci = addCut("CYL", "CYL", -1, t_.band_tool, 0, mach(x_cut, 0, b.z_from_mm), mach(x_cut, 0, b.z_from_mm));
    // Incremental (G91): an absolute C360 from C0 is a null move on a rollover axis.
    add(gcode::TurnC{360.0, F}, w + ": one turn of C", true, ci);
    feedXY(x_out, 0, t_.band_feed_mm_per_min, w + ": feed radially out", true);
    // C reads 360 on a linear axis (unwound here, the tool outside), 0 on a rollover axis.
    add(gcode::RotateC{0}, w + ": C back to 0 with the tool outside the blank");
  }

  // Face the top from +1 to 0: passes along X, stepover from the description.
  add(gcode::Comment{"step 1: face the top, z +" + formatNumber(t_.face_depth_mm) + " -> 0 [L2010]"}, "face");
  cutterFor(t_.face_tool, "face");
  rapidZ(zc, "face: clearance plane");
  {
    const double r = radius(t_.face_tool), out = env_.R + r + kOutside;
    const auto ys = lanes(env_.R - r + 1.0, t_.face_stepover_mm);  // the tool overhangs both edges by 1 mm
    double side = -1;
    for (std::size_t i = 0; i < ys.size(); ++i) {
      const double y = ys[i], reach = std::sqrt(out * out - y * y);
      const std::string w = "face pass " + std::to_string(i + 1);
      if (i == 0) {
        rapidXY(side * reach, y, w + ": above the start, outside the blank");
        rapidZ(0, w + ": down outside the blank");
      } else {
        feedXY(side * reach, y, travel_feed_, w + ": to the next pass outside the blank");
      }
      const int ci = addCut("TOP-" + std::to_string(i + 1), "TOP", -1, t_.face_tool, 0, mach(side * reach, y, 0),
                            mach(-side * reach, y, 0));
      feedXY(-side * reach, y, t_.face_feed_mm_per_min, w, true, ci);
      side = -side;
    }
    rapidZ(zc, "face: up to the clearance plane");
  }

  // Step 2: the mark (engraved line).
  add(gcode::Comment{"step 2: engrave the mark [L2012]"}, "mark");
  cutterFor(t_.mark_tool, "mark");
  // A 0.5 mm tip: plunge and engrave at a quarter of the pre-machining feed (our choice).
  const double F_mark = t_.pre_feed_mm_per_min / 4;
  rapidXY(t_.mark_from_mm.x(), t_.mark_from_mm.y(), "mark: above its start");
  rapidZ(zc, "mark: clearance plane");
  rapidZ(env_.blank_top, "mark: down to the level of the blank's top (faced 1 mm below)");
  feedZ(-t_.mark_depth_mm, F_mark, "mark: plunge", true);
  feedXY(t_.mark_to_mm.x(), t_.mark_to_mm.y(), F_mark, "mark", true);
  rapidZ(zc, "mark: up to the clearance plane");

  // Step 3: the Y notch: lanes in x inside |x| <= w/2, levels, passes along Y.
  add(gcode::Comment{"step 3: notch along Y [L2012]"}, "Y notch");
  cutterFor(t_.y_notch_tool, "Y notch");
  {
    const double r = radius(t_.y_notch_tool);
    passes(true, lanes(t_.y_notch_width_mm / 2 - r, std::min(t_.face_stepover_mm, 0.75 * 2 * r)),
           levels(t_.y_notch_depth_mm, t_.y_notch_step_mm), t_.y_notch_tool, t_.pre_feed_mm_per_min, "Y notch");
    rapidZ(zc, "Y notch: up to the clearance plane");
  }

  // Step 4: the X notch: rough leaving the allowance on the flanks and the floor, finish the
  // floor, then each flank in one climb-milling pass over the whole depth.
  add(gcode::Comment{"step 4: notch along X, rough and finish [L2014]"}, "X notch");
  cutterFor(t_.x_notch_tool, "X notch");
  const double rx = radius(t_.x_notch_tool), a = t_.x_notch_allowance_mm, w2 = t_.x_notch_width_mm / 2;
  const double step_x = std::min(t_.face_stepover_mm, 0.75 * 2 * rx);
  const auto rough_lanes = lanes(w2 - a - rx, step_x);
  passes(false, rough_lanes, levels(t_.x_notch_depth_mm - a, t_.x_notch_step_mm), t_.x_notch_tool,
         t_.pre_feed_mm_per_min, "X notch rough");
  passes(false, rough_lanes, {-t_.x_notch_depth_mm}, t_.x_notch_tool, t_.pre_feed_mm_per_min, "X notch floor");
  {
    const double out = env_.R + rx + kOutside;
    for (int s : {+1, -1}) {
      const double y = s * (w2 - rx), reach = std::sqrt(out * out - y * y);
      // Climb milling with M3: the +Y flank is cut moving -X, the -Y flank moving +X.
      const double x0 = s * reach, x1 = -s * reach;
      const std::string id = s > 0 ? "FLANK_P" : "FLANK_N";
      travel(Vector2d(x0, y), t_.x_notch_tool, id + " finish: to its start");
      const int ci = addCut(id, id, -1, t_.x_notch_tool, 0, mach(x0, y, t_.notchFloorZ()), mach(x1, y, t_.notchFloorZ()));
      feedXY(x1, y, t_.pre_feed_mm_per_min, id + " finish", true, ci);
    }
  }

  // Step 5: the facets at the allowance, each indexed to face machine +X, the tool on the
  // +X side moving -Y, its bottom at the notch floor so that the bands below stay whole.
  add(gcode::Comment{"step 5: facets at the allowance, each facing +X [L2016]"}, "facets");
  if (t_.facet_pre_tool != current_tool_) {
    rapidZ(zc, "facets: up to the clearance plane");
    cutterFor(t_.facet_pre_tool, "facets");
    rapidXY(env_.R + radius(t_.facet_pre_tool) + kOutside, 0, "facets: beside the blank");
    rapidZ(t_.notchFloorZ(), "facets: down outside the blank");
  }
  {
    struct F {
      std::string id;
      double c;
    };
    std::vector<F> list;
    const FacetSide sides[4] = {FacetSide::X1, FacetSide::Y1, FacetSide::X2, FacetSide::Y2};
    for (auto s : sides)
      for (int k = 1; k <= t_.facets_per_segment; ++k)
        list.push_back({parts::facetId(s, k), cToFace(m_, parts::facetNormalAngle(t_, s, k), 0)});
    std::stable_sort(list.begin(), list.end(), [](const F& x, const F& y) { return x.c < y.c; });
    const double xf = t_.facet_apothem_mm + t_.facet_allowance_mm + radius(t_.facet_pre_tool);
    const double L = t_.facet_path_half_length_mm;
    for (const auto& f : list) {
      const std::string w = "facet " + f.id + " (pre-cut)";
      indexC(f.c, w + ": C index with the tool outside the part");
      travel(Vector2d(xf, L), t_.facet_pre_tool, w + ": to its start");
      feedXY(xf, -L, t_.pre_feed_mm_per_min, w, true);
    }
  }
  rapidZ(zc, "facets: up to the clearance plane");
  add(gcode::RapidMachineZ{m_.tool_change.z_mm}, "end: retract to the tool-change height");
  spindleOff(wet, "end: spindle off");
  add(gcode::RotateC{0}, "end: C back to 0");
  add(gcode::ToolChange{m_.tool_change.empty_tool, false}, "end: empty the spindle");
}

void Builder::test() {
  newProgram("test", files_.test, 2002,
             "probeloop thermal test piece: the test [seed 004 L2022-L2047] - generated, do not edit");
  toolHeader({t_.test_tool});
  const int T = t_.test_tool;
  const double r = radius(T), zc = t_.cuttingZ();
  const bool wet = t_.test_coolant;
  const double ap = t_.facet_apothem_mm + r, L = t_.facet_path_half_length_mm;
  const Vector2d W = t_.waiting_position_mm;  // part frame = machine axes at C = 0
  P().program.header.push_back("the tool is set once to Z " + formatNumber(mz(zc), 4) +
                               " [part z " + formatNumber(zc) + "]; no Z word from then until after the last cut [L1986]");
  // The cut start points must lie outside the blank, or the approach would cut.
  if (std::hypot(ap, L) < env_.R + r)
    throw InputError(t_.file, 0,
                     "test.facet_path_half_length: " + formatNumber(L) +
                         " mm starts the facet cuts inside the blank (the tool at " + formatNumber(std::hypot(ap, L), 3) +
                         " mm from the axis needs at least " + formatNumber(env_.R + r, 3) + ")");
  toolChange(T, "test: tool change");
  rapidXY(W.x(), W.y(), "test: above the waiting position");
  rapidZ(0 + clearance_, "test: clearance plane");
  add(gcode::Feed{std::nullopt, std::nullopt, mz(zc), round3(travel_feed_)},
      "test: down to the cutting height beside the part (the one Z of the test)");
  for (const auto& cy : cycles_) {
    const int c = cy.cycle, j = cy.z_path, k = cy.facet;
    if (c > 0) load(cy);
    const std::string w = "test cycle " + std::to_string(c);
    const double c_x = cToFace(m_, parts::facetNormalAngle(t_, FacetSide::X1, k), 0);
    const double c_y = cToFace(m_, parts::facetNormalAngle(t_, FacetSide::Y1, k), 90);
    checkCResolution(c_x, w);
    checkCResolution(c_y, w);
    parts::ManifestCycle mc;
    mc.cycle = c;
    mc.phase = cy.phase;
    mc.c_axis_rpm_before = c > 0 ? plan_.loads.back().rpm : 0.0;
    mc.z_path = j;
    mc.facet = k;
    mc.c_x_deg = round3(c_x);
    mc.c_y_deg = round3(c_y);
    man_.cut_cycles.push_back(mc);
    add(gcode::Comment{"cycle " + std::to_string(c) + " [" + cy.phase + "]: Z path " + std::to_string(j) + ", facets " +
                       std::to_string(k)},
        w);
    cycle_first_op_.push_back(P().program.ops.size());
    spindleOn(t_.test_spindle_rpm, wet, w + ": spindle on");
    indexC(0, w + ": C 0 for the Z path");
    // Z path along +X.
    const double y = parts::zPathY(t_, j);
    const std::string zid = parts::zPathId(j);
    travel(Vector2d(t_.z_path_x_from_mm, y), T, w + ", Z path " + zid + ": to its start");
    int ci = addCut(zid, zid, c, T, 0, mach(t_.z_path_x_from_mm, y, zc), mach(t_.z_path_x_to_mm, y, zc));
    feedXY(t_.z_path_x_to_mm, y, t_.test_feed_mm_per_min, w + ", Z path " + zid, true, ci);
    // The four facets: X1 on +X moving -Y, Y1 on +Y moving -X, X2 on -X, Y2 on -Y.
    struct Cut {
      FacetSide side;
      double c;
      Vector2d from, to;
    };
    const Cut cuts[4] = {{FacetSide::X1, c_x, {ap, L}, {ap, -L}},
                         {FacetSide::Y1, c_y, {L, ap}, {-L, ap}},
                         {FacetSide::X2, c_x, {-ap, L}, {-ap, -L}},
                         {FacetSide::Y2, c_y, {L, -ap}, {-L, -ap}}};
    for (const auto& cut : cuts) {
      const std::string id = parts::facetId(cut.side, k), wf = w + ", facet " + id;
      indexC(cut.c, wf + ": C index with the tool outside the part");
      travel(cut.from, T, wf + ": to its start");
      ci = addCut(id, id, c, T, cut.c, mach(cut.from.x(), cut.from.y(), zc), mach(cut.to.x(), cut.to.y(), zc));
      feedXY(cut.to.x(), cut.to.y(), t_.test_feed_mm_per_min, wf, true, ci);
    }
    indexC(0, w + ": C back to 0 with the tool outside the part");
    travel(W, T, w + ": back to the waiting position");
    spindleOff(wet, w + ": spindle off");
    cycle_last_op_.push_back(P().program.ops.size() - 1);
  }
  add(gcode::RapidMachineZ{m_.tool_change.z_mm}, "end: retract to the tool-change height");
  add(gcode::RotateC{0}, "end: C at 0");
  add(gcode::ToolChange{m_.tool_change.empty_tool, false}, "end: empty the spindle");
}

void Builder::load(const parts::TtpCuttingCycle& cy) {
  TtpLoad l;
  l.before_cycle = cy.cycle;
  l.phase = cy.phase;
  l.requested_rpm = cy.c_axis_rpm_before;
  const std::string w = "load before test cycle " + std::to_string(cy.cycle);
  if (l.requested_rpm > 0) {
    l.rpm = std::min(l.requested_rpm, m_.c.max_turning_speed_rpm);
    const double F = round3(l.rpm * 360.0);
    // Whole turns nearest to c_turn_move, at most 277 (99720 deg): a Fanuc takes 8 digits,
    // C up to 99999.999.
    l.turns_per_move = std::clamp(static_cast<int>(std::lround(l.rpm * t_.c_turn_move_s / 60.0)), 1, kMaxTurnsPerMove);
    // A wait shorter than one pair still turns the table: fewer turns per move.
    const int fit = static_cast<int>(std::floor(t_.wait_s * l.rpm / 120.0 + 1e-9));
    if (fit >= 1) l.turns_per_move = std::min(l.turns_per_move, fit);
    l.move_s = l.turns_per_move * 360.0 / F * 60.0;
    l.pairs = static_cast<int>(std::floor(t_.wait_s / (2 * l.move_s) + 1e-9));
    l.dwell_s = round3(std::max(0.0, t_.wait_s - l.pairs * 2 * l.move_s));
    add(gcode::Comment{"wait " + formatNumber(t_.wait_s) + " s [" + cy.phase + "]: C at " + formatNumber(l.rpm) + " rpm, " +
                       std::to_string(l.pairs) + " x [+" + std::to_string(l.turns_per_move) + " turns, -" +
                       std::to_string(l.turns_per_move) + " turns]" +
                       (l.rpm < l.requested_rpm
                            ? " [" + formatNumber(l.requested_rpm) + " rpm asked; the machine's max_turning_speed]"
                            : "")},
        w);
    if (l.pairs > 0) {
      // Incremental moves, +N and -N turns: C is back where it started after every pair on
      // any control (absolute C72000 / C0 would not turn a rollover axis at all).
      add(gcode::LoopBegin{l.pairs, "_pl_load"}, w);
      add(gcode::TurnC{l.turns_per_move * 360.0, F}, w + ": C turns forward");
      add(gcode::TurnC{-l.turns_per_move * 360.0, F}, w + ": C turns back");
      add(gcode::LoopEnd{}, w);
    }
    if (l.dwell_s > 0) add(gcode::Dwell{l.dwell_s}, w + ": the rest of the wait");
  } else {
    l.dwell_s = round3(t_.wait_s);
    add(gcode::Comment{"wait " + formatNumber(t_.wait_s) + " s [" + cy.phase + "]: NC hold at C 0"}, w);
    add(gcode::Dwell{l.dwell_s}, w + ": NC hold");
  }
  plan_.loads.push_back(l);
}

}  // namespace probeloop::planner::ttp
