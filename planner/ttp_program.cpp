// The thermal-test-piece planner's building blocks (ttp_detail.hpp): ops with their notes,
// moves in part coordinates, C indexing, tool changes and the spindle, program headers, travel
// round the part and zig-zag passes.
#include "planner/ttp_detail.hpp"

#include "planner/piece_program.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"

namespace probeloop::planner::ttp {

void Builder::add(gcode::Op op, const std::string& where, bool cut, int cut_index) {
  add(std::move(op), opNote(where, cut, cut_index));
}

void Builder::add(gcode::Op op, OpNote n) {
  // Whether the spindle stands at the tool-change height (no second retract before a change).
  if (std::holds_alternative<gcode::RapidMachineZ>(op)) at_tool_change_z_ = true;
  if (std::holds_alternative<gcode::Rapid>(op) || std::holds_alternative<gcode::Feed>(op) ||
      std::holds_alternative<gcode::ProtectedMove>(op) || std::holds_alternative<gcode::ProbeMove>(op))
    at_tool_change_z_ = false;
  P().add(std::move(op), std::move(n));
}

void Builder::rapidXY(double qx, double qy, const std::string& w) { add(gcode::Rapid{mx(qx), my(qy), std::nullopt}, w); pos_ = {qx, qy}; }

void Builder::rapidZ(double z, const std::string& w) { add(gcode::Rapid{std::nullopt, std::nullopt, mz(z)}, w); }

void Builder::feedXY(double qx, double qy, double F, const std::string& w, bool cut, int ci) {
  std::optional<double> x, y;
  if (std::fabs(qx - pos_.x()) > 1e-12) x = mx(qx);
  if (std::fabs(qy - pos_.y()) > 1e-12) y = my(qy);
  if (!x && !y) return;
  add(gcode::Feed{x, y, std::nullopt, round3(F)}, w, cut, ci);
  pos_ = {qx, qy};
}

void Builder::feedZ(double z, double F, const std::string& w, bool cut) {
  add(gcode::Feed{std::nullopt, std::nullopt, mz(z), round3(F)}, w, cut);
}

void Builder::indexC(double c, const std::string& w) {
  checkCResolution(c, w);
  add(gcode::RotateC{round3(c)}, w);
}

void Builder::checkCResolution(double c, const std::string& w) const {
  const double steps = c / m_.c.resolution_deg;
  if (std::fabs(steps - std::round(steps)) > 1e-6)
    throw InputError(t_.file, 0, w + ": C " + formatNumber(c, 6) + " deg is not a multiple of the C resolution " +
                                     formatNumber(m_.c.resolution_deg) + " deg of " + m_.file);
}

void Builder::toolChange(int tool, const std::string& w) {
  if (!at_tool_change_z_) add(gcode::RapidMachineZ{m_.tool_change.z_mm}, w + ": retract to the tool-change height");
  add(gcode::ToolChange{tool, tool != m_.tool_change.empty_tool}, w);
  current_tool_ = tool;
}

void Builder::spindleOn(double rpm, bool coolant, const std::string& w) {
  add(gcode::Spindle{std::round(rpm)}, w);
  if (coolant) add(gcode::Coolant{true}, w);
  spindle_on_ = true;
}

void Builder::spindleOff(bool coolant, const std::string& w) {
  if (coolant) add(gcode::Coolant{false}, w);
  add(gcode::Spindle{0}, w);
  spindle_on_ = false;
}

void Builder::cutterFor(int tool, const std::string& w) {
  if (tool == current_tool_) return;
  const bool wet = t_.pre_machining_coolant;
  if (spindle_on_) spindleOff(wet, w + ": spindle off");
  toolChange(tool, w + ": tool change");
  spindleOn(t_.pre_spindle_rpm, wet, w + ": spindle on");
}

int Builder::addCut(const std::string& id, const std::string& feature, int cycle, int tool, double c, const Vector3d& from,
           const Vector3d& to) {
  parts::ManifestCut k;
  k.id = id;
  k.program = P().role;
  k.feature = feature;
  k.cycle = cycle;
  k.tool = tool;
  k.c_deg = round3(c);
  k.from_mm = from;
  k.to_mm = to;
  man_.cuts.push_back(k);
  return static_cast<int>(man_.cuts.size()) - 1;
}

void Builder::newProgram(const std::string& role, const std::string& file, int number, const std::string& title) {
  programs_.push_back(newNotedProgram(m_, role, file, number, title));
  current_tool_ = -1;
  spindle_on_ = false;
  P().program.header = programHeader(m_, "part: " + t_.name + ", part frame origin at " + xyz(O_) + " [machine, C = 0]");
  // Start from a known state: high, the table level (B) and at C = 0.
  add(gcode::RapidMachineZ{m_.tool_change.z_mm}, "start: retract to the tool-change height");
  if (m_.b.present) add(gcode::RotateB{0}, "start: table level (B 0)");
  add(gcode::RotateC{0}, "start: C 0");
}

void Builder::toolHeader(std::initializer_list<int> tools) {
  std::vector<int> seen;
  for (int n : tools) {
    if (std::find(seen.begin(), seen.end(), n) != seen.end()) continue;
    seen.push_back(n);
    P().program.header.push_back(toolLine(n, *t_.tool(n)));
  }
}

void Builder::travel(const Vector2d& to, int tool, const std::string& w) {
  const Vector2d from = pos_;
  const double r = radius(tool), clear = env_.R + r + kOutside;
  if ((to - from).norm() < 1e-9) return;
  // Short chords between points `kOutside` out (lane to lane) dip less than half of it.
  if (segmentOrigin(from, to) >= clear - kOutside / 2) {
    feedXY(to.x(), to.y(), travel_feed_, w);
    return;
  }
  const double ring = t_.ring_radius_mm;
  const double a0 = std::atan2(from.y(), from.x()), a1 = std::atan2(to.y(), to.x());
  double sweep = a1 - a0;
  while (sweep > kPi) sweep -= 2 * kPi;
  while (sweep < -kPi) sweep += 2 * kPi;
  const double max_step = std::min(degToRad(kMaxRingStepDeg), 2 * std::acos(clear / ring));
  const int n = std::max(1, static_cast<int>(std::ceil(std::fabs(sweep) / max_step - 1e-9)));
  feedXY(ring * std::cos(a0), ring * std::sin(a0), travel_feed_, w + ": out to the ring");
  for (int i = 1; i <= n; ++i) {
    const double a = a0 + sweep * i / n;
    feedXY(ring * std::cos(a), ring * std::sin(a), travel_feed_, w + ": around the part on the ring");
  }
  feedXY(to.x(), to.y(), travel_feed_, w + ": in from the ring");
}

void Builder::passes(bool along_y, const std::vector<double>& lane_list, const std::vector<double>& level_list, int tool, double F,
            const std::string& w) {
  const double out = env_.R + radius(tool) + kOutside;
  auto reach = [&](double lane) { return std::sqrt(out * out - lane * lane); };
  auto point = [&](double lane, double along) { return along_y ? Vector2d(lane, along) : Vector2d(along, lane); };
  std::vector<double> order = lane_list;
  double side = -1;
  bool first = true;
  for (std::size_t lv = 0; lv < level_list.size(); ++lv) {
    for (std::size_t i = 0; i < order.size(); ++i) {
      const double lane = order[i];
      const Vector2d s = point(lane, side * reach(lane)), e = point(lane, -side * reach(lane));
      const std::string where = w + " level " + std::to_string(lv + 1) + " pass " + std::to_string(i + 1);
      if (first) {
        rapidZ(env_.blank_top + clearance_, where + ": clearance plane");
        rapidXY(s.x(), s.y(), where + ": above the start, outside the blank");
        rapidZ(level_list[lv], where + ": down outside the blank");
        first = false;
      } else if (i == 0) {
        rapidZ(level_list[lv], where + ": down outside the blank");
      } else {
        feedXY(s.x(), s.y(), travel_feed_, where + ": to the next lane outside the blank");
      }
      feedXY(e.x(), e.y(), F, where, true);
      side = -side;
    }
    std::reverse(order.begin(), order.end());
  }
}

// Evenly spaced lanes over [-half, half] no farther apart than `step`.
std::vector<double> lanes(double half, double step) {
  if (half <= 1e-9) return {0.0};
  const int n = static_cast<int>(std::ceil(2 * half / step - 1e-9)) + 1;
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(-half + 2 * half * i / (n - 1));
  return v;
}

// Levels from 0 down to -depth in steps no deeper than `step`.
std::vector<double> levels(double depth, double step) {
  const int n = std::max(1, static_cast<int>(std::ceil(depth / step - 1e-9)));
  std::vector<double> v;
  for (int i = 1; i <= n; ++i) v.push_back(-depth * i / n);
  return v;
}

}  // namespace probeloop::planner::ttp
