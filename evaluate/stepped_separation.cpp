#include "evaluate/stepped_separation.hpp"

#include <cmath>

#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::evaluate::stepped {

namespace {

void requireFinite(double v, const char* what) {
  if (!std::isfinite(v)) throw GeometryError(std::string(what) + " is not a finite number");
}

}  // namespace

StageWeights stageWeights(double S, SpeedWeights rule) {
  requireFinite(S, "the spindle speed");
  if (S < 0) throw GeometryError("spindle speed " + formatNumber(S) + " rpm: a speed is >= 0 (its sense does not matter here)");
  StageWeights w;
  if (rule == SpeedWeights::Linear) {
    if (S < 1000) {
      w.stage_1000_rpm = S / 1000;  // proportion below the lowest node (Eq. 3.9's idea, with stage 2)
    } else if (S <= 3500) {
      w.stage_1000_rpm = (3500 - S) / 2500;
      w.stage_3500_rpm = (S - 1000) / 2500;
    } else if (S <= 5500) {
      w.stage_3500_rpm = (5500 - S) / 2000;
      w.stage_5500_rpm = (S - 3500) / 2000;
    } else {
      w.stage_5500_rpm = S / 5500;  // seed 000 Eq. 3.10
    }
    return w;
  }
  // seed 000 Eq. 3.7-3.10 as printed (swapped weights; notes §4.5).
  if (S < 1000) {
    w.stage_3500_rpm = S / 1000;  // Eq. 3.9: (S/1000) x e_pt1x
  } else if (S < 3500) {
    w.stage_1000_rpm = (S - 1000) / 2500;  // Eq. 3.8
    w.stage_3500_rpm = (3500 - S) / 2500;
  } else if (S <= 5500) {
    w.stage_3500_rpm = (S - 3500) / 2000;  // Eq. 3.7
    w.stage_5500_rpm = (5500 - S) / 2000;
  } else {
    w.stage_5500_rpm = S / 5500;  // Eq. 3.10
  }
  return w;
}

double thermalComponent(const parts::ComponentModel& m, const std::string& component, double T_min, double S,
                        SpeedWeights rule) {
  requireFinite(T_min, "the Temp state");
  if (T_min < 0) throw GeometryError("Temp state " + formatNumber(T_min) + " min: the thermal models start at machine start, T >= 0");
  const auto& st = m.stages(component);
  const StageWeights w = stageWeights(S, rule);
  double v = 0;
  // A zero weight skips the stage function: it need not be defined there.
  if (w.stage_1000_rpm != 0) v += w.stage_1000_rpm * m.equation(st.stage_1000_rpm)(T_min);
  if (w.stage_3500_rpm != 0) v += w.stage_3500_rpm * m.equation(st.stage_3500_rpm)(T_min);
  if (w.stage_5500_rpm != 0) v += w.stage_5500_rpm * m.equation(st.stage_5500_rpm)(T_min);
  return v;
}

double thermalPositionError_mm(double d6, double d6a, double d5, double d5a, double e_pos) {
  for (double v : {d6, d6a, d5, d5a, e_pos}) requireFinite(v, "an input of Eq. 3.5");
  return (d6 - d6a) - (d5 - d5a) - e_pos;  // seed 000 Eq. 3.5/3.6
}

double processErrorTwoWalls_mm(double dimensional_error, double e_pt, double e_pos) {
  for (double v : {dimensional_error, e_pt, e_pos}) requireFinite(v, "an input of the process error");
  return dimensional_error - e_pt - e_pos;  // seed 000 L1629
}

double processErrorOneWall_mm(double two_wall) {
  requireFinite(two_wall, "the two-wall process error");
  return two_wall / 2;  // seed 000 L1639
}

double controlErrorFeedChange_mm(const StepTerms& w2, const StepTerms& w8) {
  // seed 000 Eq. 3.11/3.12
  return (w2.d_mm - w8.d_mm) - (w2.e_pf_mm - w8.e_pf_mm) - (w2.e_pt_mm - w8.e_pt_mm) - (w2.e_pos_mm - w8.e_pos_mm);
}

double controlErrorProcessForce_mm(const StepTerms& w2, const StepTerms& w5, double e_ctrl_2400_100) {
  // seed 000 Eq. 3.15
  return (w2.d_mm - w5.d_mm) - (w2.e_pf_mm - w5.e_pf_mm) - (w2.e_pt_mm - w5.e_pt_mm) - (w2.e_pos_mm - w5.e_pos_mm) -
         e_ctrl_2400_100;
}

double controlFeedFactor(const parts::ComponentModel& m, double feed) {
  requireFinite(feed, "the feed");
  if (feed < 0) throw GeometryError("feed " + formatNumber(feed) + " mm/min: a feed is >= 0");
  const double lo = m.control_feed_low_mm_per_min, hi = m.control_feed_high_mm_per_min;
  if (feed <= lo) return 0;
  return (feed - lo) / (hi - lo);  // seed 000 Eq. 3.13/3.14
}

double controlErrorY_mm(const parts::ComponentModel& m, double dy, double feed, ControlYReading reading) {
  const double f = controlFeedFactor(m, feed);
  const auto& p = m.equation("e_ctrl_y_2400_100");  // Eq. 5.52: c0 + c1 dy + c2 dy^2
  if (p.function.family != model::Family::Polynomial || p.function.p.size() != 3)
    throw GeometryError(m.file + ": e_ctrl_y_2400_100 must be Eq. 5.52's quadratic");
  if (reading == ControlYReading::WholeBracket) return f * p(dy);  // Eq. 3.13's intent
  // seed 000 Eq. 5.54 as Table 6.7 evaluates it: factor x linear term + quadratic term, no constant.
  return f * p.function.p[1] * dy + p.function.p[2] * dy * dy;
}

double controlErrorX_mm(const parts::ComponentModel& m, double dx, double feed) {
  // seed 000 Eq. 5.55 read as Eq. 3.14: factor x Eq. 5.53.
  const double f = controlFeedFactor(m, feed);
  return f == 0 ? 0 : f * m.equation("e_ctrl_x_2400_100")(dx);
}

double eProgFromFeed(double feed) {
  requireFinite(feed, "the feed");
  if (feed < 0) throw GeometryError("feed " + formatNumber(feed) + " mm/min: a feed is >= 0");
  return kEProgPerFeed * feed;  // derived, notes §4.8
}

std::vector<std::vector<Separated>> faceToFaceWidths(const std::vector<std::vector<double>>& low,
                                                     const std::vector<std::vector<double>>& high, double u_point) {
  if (low.size() != high.size() || low.empty())
    throw GeometryError("widths: " + std::to_string(low.size()) + " rows on the low wall and " + std::to_string(high.size()) +
                        " on the high wall; the same non-zero number of rows is needed");
  requireFinite(u_point, "the point uncertainty");
  std::vector<std::vector<Separated>> w;
  for (std::size_t r = 0; r < low.size(); ++r) {
    if (low[r].size() != high[r].size() || low[r].empty())
      throw GeometryError("widths: row " + std::to_string(r + 1) + " has " + std::to_string(low[r].size()) + " and " +
                          std::to_string(high[r].size()) + " Z levels on the two walls");
    std::vector<Separated> row;
    for (std::size_t l = 0; l < low[r].size(); ++l) {
      requireFinite(low[r][l], "a wall coordinate");
      requireFinite(high[r][l], "a wall coordinate");
      row.push_back({high[r][l] - low[r][l], std::sqrt(2.0) * u_point});
    }
    w.push_back(row);
  }
  return w;
}

Separated tableTilt(double z_a, double z_b, double distance, double u_point) {
  for (double v : {z_a, z_b, distance, u_point}) requireFinite(v, "an input of the table tilt");
  if (distance == 0) throw GeometryError("table tilt: the two floor points a and b are at the same place (distance 0)");
  return {(z_b - z_a) / distance, std::sqrt(2.0) * u_point / std::abs(distance)};  // seed 000 Sec. 3.4.1, L792
}

Separated wallInclination(double x_A, double z_A, double x_B, double z_B, double u_point) {
  for (double v : {x_A, z_A, x_B, z_B, u_point}) requireFinite(v, "an input of the wall inclination");
  const double dz = z_A - z_B;
  if (dz == 0) throw GeometryError("wall inclination: points A and B are at the same Z level");
  return {(x_A - x_B) / dz, std::sqrt(2.0) * u_point / std::abs(dz)};  // seed 000 L782
}

Separated spindleTilt(const Separated& wall, const Separated& table) {
  // seed 000 L800: the wall shows spindle + table tilt, the floor the table tilt alone.
  return {wall.value - table.value, std::hypot(wall.u, table.u)};
}

Separated spindleGrowth(double h_warm, double h_cold, double u_point) {
  for (double v : {h_warm, h_cold, u_point}) requireFinite(v, "an input of the spindle growth");
  return {h_warm - h_cold, std::sqrt(2.0) * u_point};  // seed 000 L812: e_splz = h7 - h3
}

double tiltToZ_mm(double tilt, double lever_arm) {
  requireFinite(tilt, "the tilt");
  requireFinite(lever_arm, "the lever arm");
  return tilt * lever_arm;
}

std::array<AxisPrediction, 3> predict(const parts::ComponentModel& m, const PredictionPoint& p) {
  for (double v : {p.x_mm, p.y_mm, p.z_mm, p.T_min, p.spindle_rpm, p.feed_x_mm_per_min, p.feed_y_mm_per_min,
                   p.feed_z_mm_per_min, p.table_lever_arm_mm, p.spindle_lever_arm_mm})
    requireFinite(v, "a prediction input");
  const double low = m.control_feed_low_mm_per_min;
  // L1658: below 100 mm/min the feed-based errors could not be modelled and are taken as zero.
  auto process = [&](const char* id, double feed) { return feed < low ? 0.0 : m.equation(id)(feed); };
  auto thermal = [&](const char* c) { return thermalComponent(m, c, p.T_min, p.spindle_rpm, p.weights); };

  std::array<AxisPrediction, 3> out;
  out[0].axis = 'X';
  out[0].components = {
      {"e_pos_x", "Eq. 5.1 at the distance moved in X", m.equation("e_pos_x")(p.x_mm)},
      {"e_pt_x", "Eq. 5.21-5.24 at (T, S)", thermal("e_pt_x")},
      {"e_pf_x", "unnumbered e_pfx / 2 (one wall, L1639)", processErrorOneWall_mm(process("e_pf_x", p.feed_x_mm_per_min))},
      {"e_ctrl_x", "Eq. 5.55 as Eq. 3.14 (not Table 6.7's column)", controlErrorX_mm(m, p.x_mm, p.feed_x_mm_per_min)},
      {"e_cpr_x", "Eq. 5.56", process("e_cpr_x", p.feed_x_mm_per_min)},
  };
  out[1].axis = 'Y';
  out[1].components = {
      {"e_pos_y", "Eq. 5.2 at the distance moved in Y", m.equation("e_pos_y")(p.y_mm)},
      {"e_pt_y", "Eq. 5.17-5.20 at (T, S)", thermal("e_pt_y")},
      {"e_pf_y", "Eq. 5.47 / 2 (one wall, L1639)", processErrorOneWall_mm(process("e_pf_y", p.feed_y_mm_per_min))},
      {"e_ctrl_y", p.control_y == ControlYReading::Table67 ? "Eq. 5.54 as Table 6.7 reads it" : "Eq. 5.54 as Eq. 3.13",
       controlErrorY_mm(m, p.y_mm, p.feed_y_mm_per_min, p.control_y)},
      {"e_cpr_y", "Table 6.7's constant", process("e_cpr_y", p.feed_y_mm_per_min)},
  };
  const double lt = p.table_lever_arm_mm, ls = p.spindle_lever_arm_mm;
  out[2].axis = 'Z';
  out[2].components = {
      {"e_pos_z", "Eq. 5.3 at the depth", m.equation("e_pos_z")(p.z_mm)},
      {"e_splz", "Eq. 5.25-5.28 at (T, S)", thermal("e_splz")},
      // Eq. 5.46 names FeedXY, but Table 6.3 evaluates it at its "Feed Z" column (100 where the XY
      // feed is 200): the Z feed is used. Not halved (Eq. 5.51 is not).
      {"e_splf_z", "Eq. 5.46 at the Z feed (Table 6.3)", process("e_splf_z", p.feed_z_mm_per_min)},
      {"e_tt_x_z", "Eq. 5.41-5.44 x table lever arm", tiltToZ_mm(thermal("e_tt_x"), lt)},
      {"e_tt_y_z", "Eq. 5.37-5.40 x table lever arm", tiltToZ_mm(thermal("e_tt_y"), lt)},
      {"e_spd_x_z", "Eq. 5.33-5.36 x spindle lever arm", tiltToZ_mm(thermal("e_spd_x"), ls)},
      {"e_spd_y_z", "Eq. 5.29-5.32 x spindle lever arm", tiltToZ_mm(thermal("e_spd_y"), ls)},
  };
  for (auto& a : out) {
    std::vector<uncertainty::Contribution> contributions;
    for (auto& c : a.components) {
      a.total_mm += c.value_mm;
      const auto u = p.u_mm.find(c.name);
      c.u_mm = u == p.u_mm.end() ? 0 : u->second;
      if (!std::isfinite(c.u_mm) || c.u_mm < 0)
        throw GeometryError("the standard uncertainty of " + c.name + " must be a finite number >= 0");
      uncertainty::Contribution k;
      k.input = c.name + " (" + c.equation + ")";
      k.distribution = "normal";
      k.basis = u == p.u_mm.end() ? "not stated: seed 000 prints no residuals; set it from the component's regression"
                                  : "the component's regression";
      k.u = c.u_mm;
      contributions.push_back(k);
    }
    a.budget = uncertainty::combine(std::string("e_") + char(a.axis - 'A' + 'a') + " predicted", "mm", a.total_mm, contributions);
  }
  return out;
}

}  // namespace probeloop::evaluate::stepped
