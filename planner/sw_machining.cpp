// The stepped-workpiece planner's programs (sw_detail.hpp): the building blocks (ops with their
// notes and the material they move in, moves about the steps' centre, tool changes, contours),
// roughing and finishing with the warm-ups (Table 4.1, Sec. 4.1).
#include "planner/sw_detail.hpp"

#include "planner/piece_program.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::planner::sw {

void Builder::add(gcode::Op op, const std::string& where, bool cut, int cut_index) {
  add(std::move(op), opNote(where, cut, cut_index));
}

void Builder::add(gcode::Op op, OpNote n) {
  P().add(std::move(op), std::move(n));
  states_.back().push_back(material_);
}

void Builder::rapidXY(const Vector2d& q, const std::string& w) {
  add(gcode::Rapid{mx(q.x()), my(q.y()), std::nullopt}, w);
  pos_ = q;
}

void Builder::feedXY(const Vector2d& q, double F, const std::string& w, bool cut, int ci) {
  std::optional<double> x, y;
  if (std::fabs(q.x() - pos_.x()) > 1e-12) x = mx(q.x());
  if (std::fabs(q.y() - pos_.y()) > 1e-12) y = my(q.y());
  if (!x && !y) return;
  add(gcode::Feed{x, y, std::nullopt, round3(F)}, w, cut, ci);
  pos_ = q;
}

void Builder::feedZ(double z, double F, const std::string& w, bool cut) {
  add(gcode::Feed{std::nullopt, std::nullopt, mz(z), round3(F)}, w, cut);
}

int Builder::addCut(const std::string& id, const std::string& feature, int step, const Vector2d& from, const Vector2d& to, double z) {
  parts::ManifestCut k;
  k.id = id;
  k.program = P().role;
  k.feature = feature;
  k.cycle = step;
  k.tool = tool_->number;
  k.start_s = k.end_s = NAN;  // set by walk()
  k.from_mm = mach(from, z);
  k.to_mm = mach(to, z);
  man_.cuts.push_back(k);
  return static_cast<int>(man_.cuts.size()) - 1;
}

void Builder::newProgram(const std::string& role, const std::string& file, int number, const std::string& title) {
  programs_.push_back(newNotedProgram(m_, role, file, number, title));
  states_.emplace_back();
  P().program.header = programHeader(m_, "part: " + w_.name + ", experiment " + e_->id + "; part frame origin at " + xyz(O_) +
                                               " [machine], the steps centred on X " + formatNumber(O_.x() + c_, 4) + " Y " +
                                               formatNumber(O_.y() + c_, 4));
  add(gcode::RapidMachineZ{m_.tool_change.z_mm}, "start: retract to the tool-change height");
  if (m_.b.present) add(gcode::RotateB{0}, "start: table level (B 0)");
  if (m_.c.present) add(gcode::RotateC{0}, "start: C 0");
}

void Builder::toolChange(int tool, const std::string& w) {
  add(gcode::RapidMachineZ{m_.tool_change.z_mm}, w + ": retract to the tool-change height");
  add(gcode::ToolChange{tool, tool != m_.tool_change.empty_tool}, w);
}

void Builder::end(bool spindle) {
  add(gcode::RapidMachineZ{m_.tool_change.z_mm}, "end: retract to the tool-change height");
  if (spindle) add(gcode::Spindle{0}, "end: spindle off");
  add(gcode::ToolChange{m_.tool_change.empty_tool, false}, "end: empty the spindle");
}

std::string Builder::toolLine() const {
  return planner::toolLine(tool_->number, *tool_);
}

void Builder::contour(double s, double F, const std::string& w, int ci, bool cut) {
  const Vector2d corners[4] = {{s, s}, {s, -s}, {-s, -s}, {-s, s}};
  for (const auto& q : corners) feedXY(q, F, w, cut, ci);
}

void Builder::roughing() {
  newProgram("roughing", files_.roughing, 3001,
             "probeloop stepped workpiece: roughing to the finishing margin [seed 000 L695] - generated, do not edit");
  P().program.header.push_back(toolLine());
  const auto& g = w_.machining;
  const double mrg = w_.finishing_margin_mm, B = std::max(w_.blank_x_mm, w_.blank_y_mm) / 2;
  toolChange(tool_->number, "roughing: tool change");
  add(gcode::Spindle{std::round(g.roughing_spindle_rpm)}, "roughing: spindle on");
  rapidZ(z_clear_, "roughing: clearance plane");
  // Entry beside the blank on the line of a contour's +Y edge, the tool `lead` outside it.
  const double x_out = B + r_ + w_.machining.lead_mm;
  double z_from = w_.blankTopZ();
  int level = 0;
  for (std::size_t k = 0; k < sizes_.size(); ++k) {
    const double z_to = -w_.steps[k].floor_depth_mm + mrg;
    const int n = std::max(1, static_cast<int>(std::ceil((z_from - z_to) / g.roughing_depth_per_level_mm - 1e-9)));
    const double inner = sizes_[k] / 2 + mrg + r_;
    std::vector<double> rings;  // outside in, the innermost leaving the margin
    for (double s = inner; s - r_ < B; s += step_) rings.push_back(s);
    std::reverse(rings.begin(), rings.end());
    for (int i = 1; i <= n; ++i) {
      const double z = z_from - (z_from - z_to) * i / n;
      const std::string w = "roughing level " + std::to_string(++level) + " (z " + formatNumber(z, 3) + ", outside step " +
                            std::to_string(k + 1) + ")";
      add(gcode::Comment{w}, w);
      rapidXY(Vector2d(-x_out, rings.front()), w + ": beside the blank");
      rapidZ(z, w + ": down beside the blank");
      for (std::size_t j = 0; j < rings.size(); ++j) {
        const double s = rings[j];
        feedXY(Vector2d(-s, s), g.roughing_feed_xy_mm_per_min, w + (j ? ": in to the next contour" : ": in"), true);
        contour(s, g.roughing_feed_xy_mm_per_min, w + " contour " + std::to_string(j + 1), -1);
      }
      rapidZ(z_clear_, w + ": up to the clearance plane");
    }
    z_from = z_to;
  }
  material_.blank = false;  // from here on the roughed shape
  end(true);
}

void Builder::stepPath(std::size_t k, bool air, const std::string& w) {
  const auto& cond = e_->steps[k];
  const double F = cond.feed_xy_mm_per_min, mrg = w_.finishing_margin_mm;
  const double h = sizes_[k] / 2, s_in = h + r_, s_fin = h + mrg + r_;
  const bool last = k + 1 == sizes_.size();
  const double outer = last ? std::max(w_.blank_x_mm, w_.blank_y_mm) / 2 : sizes_[k + 1] / 2 + mrg;
  const double s_out = outer + 1.0 - r_;  // the tool's edge 1 mm past the ring's roughed edge
  std::vector<double> rings;
  for (double s = s_out; s > s_fin + 1e-9; s -= step_) rings.push_back(s);
  rings.push_back(s_fin);  // the innermost leaves the wall's margin to the wall pass
  const std::string gk = "S" + std::to_string(k + 1);
  const double z = air ? z_clear_ : -w_.steps[k].floor_depth_mm + floorShift(k);
  auto ci = [&](const std::string& id, const std::string& feature, const Vector2d& a, const Vector2d& b) {
    return air ? -1 : addCut(id, feature, static_cast<int>(k + 1), a, b, z);
  };
  // Floor ring: down above the outermost contour's corner, plunge, contours outside in.
  if (pos_ != Vector2d(-rings.front(), rings.front()) || air) rapidXY(Vector2d(-rings.front(), rings.front()), w + ": above the floor");
  if (!air) {
    rapidZ(z + mrg + 1.0, w + ": down to 1 mm above the roughed floor");
    feedZ(z, cond.feed_z_mm_per_min, w + ": plunge to the floor", true);
  }
  for (std::size_t j = 0; j < rings.size(); ++j) {
    const double s = rings[j];
    const int c = ci(gk + "_F-" + std::to_string(j + 1), gk + "_F", Vector2d(-s, s), Vector2d(-s, s));
    if (j) feedXY(Vector2d(-s, s), F, w + ": floor, in to the next contour", !air);  // before the cut's from_mm
    contour(s, F, w + ": floor contour " + std::to_string(j + 1), c, !air);
  }
  if (!air) material_.tops_finished = static_cast<int>(k) + 2;
  // Walls, clockwise from +Y: YP moving +X, XP moving -Y, YN moving -X, XN moving +Y.
  struct Wall {
    const char* side;
    Vector2d n, dir;
    int comp;  // index in parts::kSwWalls
  };
  const Wall walls[4] = {{"YP", {0, 1}, {1, 0}, 2}, {"XP", {1, 0}, {0, -1}, 0}, {"YN", {0, -1}, {-1, 0}, 3}, {"XN", {-1, 0}, {0, 1}, 1}};
  // The tool centre's distance from the centre line for each wall (compensated).
  const auto s_of = [&](const Wall& wl) { return air ? s_in : s_in - wallShift(k, wl.comp); };
  // Where wall i's path line meets wall j's (adjacent): x from the X wall, y from the Y wall.
  const auto corner = [&](const Wall& a, const Wall& b) {
    const Wall& xw = a.n.x() != 0 ? a : b;
    const Wall& yw = a.n.x() != 0 ? b : a;
    return Vector2d(xw.n.x() * s_of(xw), yw.n.y() * s_of(yw));
  };
  if (e_->transition == "continuous") {
    feedXY(corner(walls[3], walls[0]), F, w + ": in to the wall contour", !air);
    for (int i = 0; i < 4; ++i) {
      const auto& wl = walls[i];
      const Vector2d a = corner(walls[(i + 3) % 4], wl), b = corner(wl, walls[(i + 1) % 4]);
      const int c = ci(gk + "_" + wl.side, gk + "_" + wl.side, a, b);
      feedXY(b, F, w + ": wall " + gk + "_" + wl.side + " (continuous path)", !air, c);
    }
  } else {
    const double e = h + mrg + r_ + w_.machining.lead_mm;  // past the roughed ends by the lead
    const double Ft = e_->transition_feed_mm_per_min;
    for (int i = 0; i < 4; ++i) {
      const auto& wl = walls[i];
      const Vector2d a = s_of(wl) * wl.n - e * wl.dir, b = s_of(wl) * wl.n + e * wl.dir;
      feedXY(a, Ft, w + ": " + e_->transition + " transition to wall " + gk + "_" + wl.side + " (" + formatNumber(Ft) + " mm/min)");
      const int c = ci(gk + "_" + wl.side, gk + "_" + wl.side, a, b);
      feedXY(b, F, w + ": wall " + gk + "_" + wl.side, !air, c);
    }
  }
  if (!air) material_.walls_finished = static_cast<int>(k) + 1;
  rapidZ(z_clear_, w + ": up to the clearance plane");
}

void Builder::finishing() {
  newProgram("finishing", files_.finishing, 3002,
             "probeloop stepped workpiece: experiment " + e_->id + " [seed 000 Table 4.1, Sec. 4.1] - generated, do not edit");
  auto& hd = P().program.header;
  hd.push_back(toolLine() + ", runout " + formatNumber(e_->tool_runout_mm * 1e3) + " um (Table 4.1; not in the path)");
  hd.push_back(e_->id + ": " + e_->purpose);
  std::string sz;
  for (double s : sizes_) sz += (sz.empty() ? "" : "/") + formatNumber(s);
  hd.push_back("steps " + sz + " mm, transition " + e_->transition +
               (e_->transition == "continuous" ? std::string() : " at " + formatNumber(e_->transition_feed_mm_per_min) + " mm/min"));
  toolChange(tool_->number, "finishing: tool change");
  rapidZ(z_clear_, "finishing: clearance plane");
  const double mrg = w_.finishing_margin_mm;
  for (std::size_t k = 0; k < sizes_.size(); ++k) {
    const auto& cond = e_->steps[k];
    const std::string w = "step " + std::to_string(k + 1);
    step_first_op_.push_back(P().program.ops.size());
    add(gcode::Comment{w + ": feed XY " + formatNumber(cond.feed_xy_mm_per_min) + ", Z " + formatNumber(cond.feed_z_mm_per_min) +
                       " mm/min, " + formatNumber(cond.spindle_speed_rpm) + " rpm"},
        w);
    if (k == 0) {
      add(gcode::Spindle{std::round(cond.spindle_speed_rpm)}, w + ": spindle on");
      // The top face: lanes along X from outside the roughed top square, 1 mm past its edges.
      const double H = sizes_[0] / 2 + mrg, x_out = H + r_ + w_.machining.lead_mm;
      std::vector<double> ys;
      for (double y = -H + r_ - 1.0; ; y += step_) {
        ys.push_back(std::min(y, H - r_ + 1.0));
        if (y >= H - r_ + 1.0 - 1e-9) break;
      }
      double side = -1;
      for (std::size_t i = 0; i < ys.size(); ++i) {
        const Vector2d a(side * x_out, ys[i]), b(-side * x_out, ys[i]);
        if (i == 0) {
          rapidXY(a, w + ": top, beside the top step");
          rapidZ(0, w + ": top, down beside the top step");
        } else {
          feedXY(a, cond.feed_xy_mm_per_min, w + ": top, to the next lane beside the top step");
        }
        const int c = addCut("TOP-" + std::to_string(i + 1), "TOP", 1, a, b, 0);
        feedXY(b, cond.feed_xy_mm_per_min, w + ": top lane " + std::to_string(i + 1), true, c);
        side = -side;
      }
      material_.tops_finished = 1;
      rapidZ(z_clear_, w + ": top, up to the clearance plane");
    }
    stepPath(k, false, w);
    step_last_op_.push_back(P().program.ops.size() - 1);
    if (k + 1 < sizes_.size()) {
      // Warm-up before the next step (L992, L739-741): at its speed.
      const double S = e_->steps[k + 1].spindle_speed_rpm;
      const std::string wu = "warm-up before step " + std::to_string(k + 2);
      add(gcode::Comment{wu + ": spindle idle at " + formatNumber(S) + " rpm for " + formatNumber(w_.warm_up_idle_s) + " s" +
                         (w_.warm_up_axis_manoeuvre ? ", then the axis manoeuvre (that step's path in the air)" : "")},
          wu);
      add(gcode::Spindle{std::round(S)}, wu + ": spindle at the next step's speed");
      add(gcode::Dwell{w_.warm_up_idle_s}, wu + ": spindle idle");
      if (w_.warm_up_axis_manoeuvre) stepPath(k + 1, true, wu + ": axis manoeuvre");
    }
  }
  end(true);
}

}  // namespace probeloop::planner::sw
