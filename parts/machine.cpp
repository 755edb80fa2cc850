#include "parts/machine.hpp"

#include "core/units.hpp"

#include <algorithm>
#include <cctype>
#include <stdexcept>
#include <vector>

#include "core/error.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::parts {

const char* dialectName(Dialect d) { return d == Dialect::LinuxCnc ? "linuxcnc" : "fanuc"; }

namespace {

LinearAxis readLinear(YamlMap m) {
  LinearAxis a;
  a.min_mm = m.quantity("min", Dimension::Length);
  a.max_mm = m.quantity("max", Dimension::Length);
  a.max_feed_mm_per_min = m.quantity("max_feed", Dimension::Feed);
  a.resolution_mm = m.quantity("resolution", Dimension::Micrometre) * 1e-3;
  if (!(a.max_mm > a.min_mm)) m.fail("max", "travel max must exceed min");
  if (!(a.max_feed_mm_per_min > 0)) m.fail("max_feed", "must be positive");
  if (!(a.resolution_mm > 0)) m.fail("resolution", "must be positive");
  m.finish();
  return a;
}

RotaryAxis readRotary(YamlMap m, bool with_sense) {
  RotaryAxis a;
  a.present = true;
  a.continuous = m.booleanOr("continuous", false);
  if (!a.continuous) {
    a.min_deg = m.quantity("min", Dimension::Angle);
    a.max_deg = m.quantity("max", Dimension::Angle);
    if (!(a.max_deg > a.min_deg)) m.fail("max", "travel max must exceed min");
  }
  a.max_speed_rpm = m.quantity("max_speed", Dimension::RotSpeed);
  if (!(a.max_speed_rpm > 0)) m.fail("max_speed", "must be positive");
  a.max_turning_speed_rpm = m.quantityOr("max_turning_speed", Dimension::RotSpeed, a.max_speed_rpm);
  if (!(a.max_turning_speed_rpm >= a.max_speed_rpm))
    m.fail("max_turning_speed", "the turning mode is at least as fast as positioning (max_speed)");
  if (a.max_turning_speed_rpm != a.max_speed_rpm && !a.continuous)
    m.fail("max_turning_speed", "a turning mode needs a continuous axis (continuous: true)");
  a.resolution_deg = m.quantity("resolution", Dimension::Angle);
  if (with_sense) {
    a.positive_is_clockwise =
        m.choice("positive_rotation", {"clockwise", "counterclockwise"}) == "clockwise";
  } else if (m.has("positive_rotation")) {
    // A tilting axis: clockwise (seen from +X for A, +Y for B) unless stated, as on a
    // workpiece-side primed axis (ISO 841).
    a.positive_is_clockwise =
        m.choice("positive_rotation", {"clockwise", "counterclockwise"}) == "clockwise";
  }
  m.finish();
  return a;
}

}  // namespace

Eigen::Vector2d turnedByTable(const Eigen::Vector2d& v, double c_deg, bool positive_is_clockwise) {
  const double a = degToRad(tableTurnSign(positive_is_clockwise) * c_deg);
  return {std::cos(a) * v.x() - std::sin(a) * v.y(), std::sin(a) * v.x() + std::cos(a) * v.y()};
}

Eigen::Vector2d unturnedByTable(const Eigen::Vector2d& v, double c_deg, bool positive_is_clockwise) {
  return turnedByTable(v, -c_deg, positive_is_clockwise);
}

std::array<bool, 3> workpieceSideAxes(const std::string& code) {
  std::array<bool, 3> side{false, false, false};
  if (code.empty()) return side;
  const auto open = code.find('['), close = code.rfind(']');
  if (open == std::string::npos || close == std::string::npos || close < open)
    throw std::invalid_argument("expected a code like \"V[w C' Y X Z t]\" (ISO 10791-1: axes from the workpiece w to the tool t)");
  // The prime as ISO documents print it (U+2032, bytes E2 80 B2) is the ASCII apostrophe.
  const std::string raw = code.substr(open + 1, close - open - 1), prime = "\u2032";
  std::string body;
  for (std::size_t k = 0; k < raw.size();) {
    if (raw.compare(k, prime.size(), prime) == 0) {
      body += '\'';
      k += prime.size();
      continue;
    }
    if (static_cast<unsigned char>(raw[k]) >= 0x80)
      throw std::invalid_argument("unexpected non-ASCII character in the code");
    body += raw[k++];
  }
  // Tokens: letters with optional digits and prime; brackets group gantry axes.
  std::vector<std::string> tokens;
  std::string cur;
  for (char ch : body) {
    if (std::isalnum(static_cast<unsigned char>(ch)) || ch == '\'') {
      cur += ch;
    } else {
      if (!cur.empty()) tokens.push_back(cur);
      cur.clear();
    }
  }
  if (!cur.empty()) tokens.push_back(cur);
  if (tokens.empty() || tokens.front() != "w" || tokens.back() != "t")
    throw std::invalid_argument("the chain must run from the workpiece 'w' to the tool 't'");
  const bool has_frame = std::find(tokens.begin(), tokens.end(), "b") != tokens.end();
  bool before_frame = true;
  for (const auto& t : tokens) {
    if (t == "b") {
      before_frame = false;
      continue;
    }
    const int axis = t[0] == 'X' ? 0 : t[0] == 'Y' ? 1 : t[0] == 'Z' ? 2 : -1;
    if (axis < 0) continue;
    const bool primed = t.back() == '\'';
    // With the frame b in the code, the axes before it carry the workpiece; without it,
    // ISO 841's prime marks an axis that moves the workpiece.
    side[static_cast<std::size_t>(axis)] = has_frame ? before_frame : primed;
  }
  return side;
}

Machine loadMachine(const std::string& path) {
  YamlMap root(loadYamlFile(path), path, "");
  Machine mc;
  mc.file = path;
  if (root.choice("kind", {"machine"}) != "machine") root.fail("kind", "expected 'machine'");
  mc.name = root.string("name");
  mc.iso10791_code = root.stringOr("iso10791_code", "");
  mc.dialect = root.choice("dialect", {"linuxcnc", "fanuc"}) == "linuxcnc" ? Dialect::LinuxCnc
                                                                          : Dialect::FanucMacroB;
  YamlMap axes = root.map("axes");
  mc.x = readLinear(axes.map("X"));
  mc.y = readLinear(axes.map("Y"));
  mc.z = readLinear(axes.map("Z"));
  if (auto a = axes.mapIfPresent("A")) mc.a = readRotary(*a, false);
  if (auto b = axes.mapIfPresent("B")) mc.b = readRotary(*b, false);
  if (mc.a.present && mc.b.present) axes.fail("A", "a machine with both A and B is not supported (one tilting axis carries the C table)");
  if (auto c = axes.mapIfPresent("C")) mc.c = readRotary(*c, true);
  axes.finish();
  mc.rapid_feed_mm_per_min = root.quantity("rapid_feed", Dimension::Feed);
  if (!(mc.rapid_feed_mm_per_min > 0)) root.fail("rapid_feed", "must be positive");

  if (mc.c.present) {
    YamlMap table = root.map("c_axis");
    mc.c_axis_centre_mm.x() = table.quantity("centre_x", Dimension::Length);
    mc.c_axis_centre_mm.y() = table.quantity("centre_y", Dimension::Length);
    mc.table_surface_z_mm = table.quantity("table_surface_z", Dimension::Length);
    table.finish();
  } else {
    // No rotary table: only the table surface.
    YamlMap table = root.map("table");
    mc.table_surface_z_mm = table.quantity("surface_z", Dimension::Length);
    table.finish();
  }
  if (auto ba = root.mapIfPresent("b_axis")) {
    if (!mc.b.present) ba->fail("centre_x", "b_axis needs a B axis under axes");
    mc.b_axis_centre_xz_mm = Eigen::Vector2d(ba->quantity("centre_x", Dimension::Length),
                                             ba->quantity("centre_z", Dimension::Length));
    ba->finish();
  }
  if (auto aa = root.mapIfPresent("a_axis")) {
    if (!mc.a.present) aa->fail("centre_y", "a_axis needs an A axis under axes");
    mc.a_axis_centre_yz_mm = Eigen::Vector2d(aa->quantity("centre_y", Dimension::Length),
                                             aa->quantity("centre_z", Dimension::Length));
    aa->finish();
  }
  try {
    mc.workpiece_side = workpieceSideAxes(mc.iso10791_code);
  } catch (const std::invalid_argument& e) {
    root.fail("iso10791_code", e.what());
  }

  const std::string wo = root.choice("work_offset", {"G54", "G55", "G56", "G57", "G58", "G59"});
  mc.work_offset = wo[2] - '3';  // G54 -> 1 ... G59 -> 6

  YamlMap tc = root.map("tool_change");
  mc.tool_change.time_s = tc.quantity("time", Dimension::Duration);
  mc.tool_change.z_mm = tc.quantity("z", Dimension::Length);
  mc.tool_change.empty_tool = tc.integer("empty_tool");
  mc.tool_change.holder_diameter_mm = tc.quantityOr("holder_diameter", Dimension::Length, 63);
  if (!(mc.tool_change.holder_diameter_mm > 0)) tc.fail("holder_diameter", "must be positive");
  if (mc.tool_change.time_s < 0) tc.fail("time", "must not be negative");
  if (mc.tool_change.z_mm < mc.z.min_mm || mc.tool_change.z_mm > mc.z.max_mm)
    tc.fail("z", "tool-change Z is outside the Z travel");
  tc.finish();

  YamlMap pr = root.map("probe");
  mc.probe.tool = pr.integer("tool");
  mc.probe.length_mm = pr.quantity("length", Dimension::Length);
  mc.probe.tip_diameter_mm = pr.quantity("tip_diameter", Dimension::Length);
  mc.probe.repeatability_2sigma_um = pr.quantity("repeatability_2sigma", Dimension::Micrometre);
  mc.probe.tool_change_repeatability_2sigma_um = pr.quantityOr("tool_change_repeatability_2sigma", Dimension::Micrometre, NAN);
  if (pr.has("tool_change_repeatability_2sigma") && !(mc.probe.tool_change_repeatability_2sigma_um >= 0))
    pr.fail("tool_change_repeatability_2sigma", "must be >= 0");
  mc.probe.stylus_diameter_mm = pr.quantityOr("stylus_diameter", Dimension::Length, 0.75 * mc.probe.tip_diameter_mm);
  mc.probe.stylus_length_mm = pr.quantityOr("stylus_length", Dimension::Length, 50);
  mc.probe.body_diameter_mm = pr.quantityOr("body_diameter", Dimension::Length, 63);
  mc.probe.max_overtravel_mm = pr.quantityOr("max_overtravel", Dimension::Length, 5);
  if (!(mc.probe.stylus_diameter_mm > 0) || mc.probe.stylus_diameter_mm > mc.probe.tip_diameter_mm)
    pr.fail("stylus_diameter", "must be positive and at most the tip diameter");
  if (!(mc.probe.stylus_length_mm > 0) || mc.probe.stylus_length_mm > mc.probe.length_mm)
    pr.fail("stylus_length", "must be positive and at most the probe length");
  if (!(mc.probe.body_diameter_mm > 0)) pr.fail("body_diameter", "must be positive");
  if (!(mc.probe.max_overtravel_mm > 0)) pr.fail("max_overtravel", "must be positive");
  if (mc.probe.tool <= 0) pr.fail("tool", "probe tool number must be positive");
  if (mc.probe.tool == mc.tool_change.empty_tool)
    pr.fail("tool", "probe tool number equals tool_change.empty_tool");
  if (!(mc.probe.length_mm > 0)) pr.fail("length", "must be positive");
  if (!(mc.probe.tip_diameter_mm > 0)) pr.fail("tip_diameter", "must be positive");
  if (!(mc.probe.repeatability_2sigma_um >= 0)) pr.fail("repeatability_2sigma", "must be >= 0");
  pr.finish();
  root.finish();
  return mc;
}

}  // namespace probeloop::parts
