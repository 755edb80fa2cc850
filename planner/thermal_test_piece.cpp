#include "planner/thermal_test_piece.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "parts/piece_kinds.hpp"
#include "planner/angles.hpp"
#include "planner/piece_program.hpp"
#include "planner/ttp_detail.hpp"

namespace probeloop::planner {

namespace ttp {

Builder::Builder(const ThermalTestPiece& t, const std::vector<parts::NominalFeature>& features,
        const std::vector<parts::EvaluationRule>& evaluation, const parts::Machine& m, parts::Dialect d)
    : t_(t), m_(m), dialect_(d), env_(t), files_(ttpFiles(d)), features_(features), evaluation_(evaluation) {
  if (!m.c.present)
    throw InputError(m.file, 0, "axes.C: the thermal test piece needs a rotary table (C axis); " + m.name + " has none");
  O_ = parts::partOriginOnMachine(t, m.c_axis_centre_mm, m.table_surface_z_mm);
  cw_ = m.c.positive_is_clockwise;
  checkLayout();
  travel_feed_ = std::min({m.rapid_feed_mm_per_min, m.x.max_feed_mm_per_min, m.y.max_feed_mm_per_min, m.z.max_feed_mm_per_min});
  clearance_ = t.probing.clearance_mm;
  for (int n : {t.band_tool, t.face_tool, t.mark_tool, t.y_notch_tool, t.x_notch_tool, t.facet_pre_tool, t.test_tool}) {
    const double r = radius(n);
    if (!(t.ring_radius_mm > env_.R + r + kOutside + 1e-9))
      throw InputError(t.file, 0,
                       "test.ring_radius: " + formatNumber(t.ring_radius_mm) + " mm leaves tool T" + std::to_string(n) +
                                      " (d" + formatNumber(2 * r) + ") less than " + formatNumber(kOutside) +
                                      " mm outside the blank (needs more than " + formatNumber(env_.R + r + kOutside) + " mm)");
  }
}

ThermalTestPiecePlan Builder::build() {
  cycles_ = parts::cuttingCycles(t_);
  for (std::size_t i = 0; i < features_.size(); ++i) {
    parts::ManifestFeature f;
    f.nominal = features_[i];
    f.position = static_cast<int>(i + 1);  // the inspection probes them in this order
    man_.features.push_back(f);
  }
  preMachining();
  test();
  inspection();
  walk();
  manifest();
  plan_.programs = std::move(programs_);
  plan_.manifest = std::move(man_);
  plan_.cmm_points_csv = cmmCsv();
  plan_.test_cutting_z_mm = round4(O_.z() + t_.cuttingZ());
  return std::move(plan_);
}

const parts::NominalFeature& Builder::feature(const std::string& id) const {
  for (const auto& f : features_)
    if (f.id == id) return f;
  throw std::logic_error("thermal test piece: the features handed to the planner lack " + id);
}

void Builder::checkLayout() const {
  const double a = t_.facet_apothem_mm, wx = t_.x_notch_width_mm / 2, wy = t_.y_notch_width_mm / 2;
  const double rt = m_.probe.tip_diameter_mm / 2;
  const FacetSide sides[4] = {FacetSide::X1, FacetSide::Y1, FacetSide::X2, FacetSide::Y2};
  // Every facet's centre on a segment: a facet whose centre lies in a notch is cut away.
  for (auto s : sides)
    for (int k = 1; k <= t_.facets_per_segment; ++k) {
      const double th = degToRad(parts::facetNormalAngle(t_, s, k));
      const Vector2d c = a * Vector2d(std::cos(th), std::sin(th));
      const bool in_x = !(std::fabs(c.y()) > wx), in_y = !(std::fabs(c.x()) > wy);
      if (in_x || in_y)
        throw InputError(t_.file, 0,
                         std::string(in_x ? "pre_machining.x_notch.width: " : "pre_machining.y_notch.width: ") +
                             formatNumber(in_x ? t_.x_notch_width_mm : t_.y_notch_width_mm) + " mm cuts facet " +
                             parts::facetId(s, k) + " away: its centre (x " + formatNumber(c.x(), 2) + ", y " +
                             formatNumber(c.y(), 2) + " mm) lies in the notch (|" + (in_x ? "y" : "x") + "| < " +
                             formatNumber(in_x ? wx : wy) +
                             " mm); narrow the notch or turn the facets (pre_machining.facets.first_normal_angle, pitch)");
    }
  topPoints();  // throws when the notches leave no room for them
  // The flank points at 1/4 and 3/4 of each flank beside the Y notch keep a tip radius from its ends.
  const double flank = feature("FLANK_P").half_u_mm - wy;
  if (!(flank >= 4 * rt))
    throw InputError(t_.file, 0,
                     "pre_machining.x_notch.width: " + formatNumber(t_.x_notch_width_mm) + " mm leaves flanks " +
                         formatNumber(flank, 2) + " mm long beside the Y notch; the inspection's flank points need " +
                         formatNumber(4 * rt) + " mm (4 tip radii)");
  // The test's facet cuts run with the tool's bottom at the cutting height, 0.1 mm below the
  // notch floor: where a facet's chord passes over the notch the tool re-cuts the floor in a
  // strip (a facet normal's projection between a and a + 2r). A Z-path point there (or
  // within kStripMargin of it) would measure another cycle's cut.
  const double r = radius(t_.test_tool), ap = a + r, L = t_.facet_path_half_length_mm;
  for (auto s : sides)
    for (int k = 1; k <= t_.facets_per_segment; ++k) {
      const double th = degToRad(parts::facetNormalAngle(t_, s, k));
      const Vector2d n(std::cos(th), std::sin(th)), u(-n.y(), n.x());
      const Vector2d A = ap * n + L * u, B = ap * n - L * u;
      for (int j = 1; j <= t_.z_paths; ++j)
        for (double x : t_.z_path_points_along_mm)
          for (double d : t_.z_path_points_across_mm) {
            const Vector2d p(x, parts::zPathY(t_, j) + d);
            const double gap = pointSegment(p, A, B) - r;
            if (gap < kStripMargin)
              throw InputError(t_.file, 0,
                               "inspection.z_path_points.along: the point x " + formatNumber(p.x()) + " y " +
                                   formatNumber(p.y()) + " mm of Z path " + parts::zPathId(j) +
                                   (gap < 0 ? " lies in" : " lies " + formatNumber(gap, 2) + " mm from") +
                                   " the strip of notch floor the test's cuts of facet " + parts::facetId(s, k) +
                                   " re-cut at the cutting height (in another cycle than the path); keep it " +
                                   formatNumber(kStripMargin) + " mm away (docs/thermal-test-piece.md §5)");
          }
    }
}

std::array<Vector2d, 3> Builder::topPoints() const {
  const double rt = m_.probe.tip_diameter_mm / 2, a = t_.facet_apothem_mm, r_o = a - 2 * rt;
  const double wx = t_.x_notch_width_mm / 2, wy = t_.y_notch_width_mm / 2;
  auto refuse = [&](const std::string& key, const std::string& why) {
    throw InputError(t_.file, 0, key + ": " + why + ": no room on the top for the inspection's TOP points, which keep " +
                                     formatNumber(2 * rt) + " mm (a tip diameter) from the notches and inside the facets' " +
                                     formatNumber(r_o, 2) + " mm circle (apothem - a tip diameter)");
  };
  const double s_lo = (wx + 2 * rt) / r_o, c_hi = (wy + 2 * rt) / r_o;
  if (!(r_o > 0 && s_lo < 1)) refuse("pre_machining.x_notch.width", formatNumber(t_.x_notch_width_mm) + " mm");
  if (!(c_hi < 1)) refuse("pre_machining.y_notch.width", formatNumber(t_.y_notch_width_mm) + " mm");
  const double lo = std::asin(s_lo), hi = std::acos(c_hi);
  if (!(lo < hi))
    refuse("pre_machining.x_notch.width", formatNumber(t_.x_notch_width_mm) + " mm with the y_notch " +
                                              formatNumber(t_.y_notch_width_mm) + " mm");
  const double mid = (lo + hi) / 2;
  const double r_in = std::max(wx / std::sin(mid), wy / std::cos(mid)) + 2 * rt;
  if (!(r_in < r_o))
    refuse("pre_machining.x_notch.width", formatNumber(t_.x_notch_width_mm) + " mm with the y_notch " +
                                              formatNumber(t_.y_notch_width_mm) + " mm");
  auto at = [](double r, double ang) { return Vector2d(r * std::cos(ang), r * std::sin(ang)); };
  return {at(r_o, lo + 0.3 * (hi - lo)), at(r_o, lo + 0.7 * (hi - lo)), at(r_in, mid)};
}

}  // namespace ttp

using parts::ThermalTestPiece;
using ttp::Builder;
using ttp::Collisions;
using ttp::Envelope;
using ttp::walkerTools;

TtpFiles ttpFiles(parts::Dialect d) {
  const std::string ext = programExtension(d);
  TtpFiles f;
  f.pre_machining = "pre_machining" + ext;
  f.test = "thermal_test" + ext;
  f.inspection = "inspection" + ext;
  return f;
}

double cToFace(const parts::Machine& m, double part_angle_deg, double machine_angle_deg) {
  // machine angle = part angle + s C (parts::tableTurnSign).
  return wrapDeg360((machine_angle_deg - part_angle_deg) / parts::tableTurnSign(m.c.positive_is_clockwise));
}

ThermalTestPiecePlan planThermalTestPiece(const ThermalTestPiece& t, const std::vector<parts::NominalFeature>& features,
                                          const std::vector<parts::EvaluationRule>& evaluation, const parts::Machine& m,
                                          parts::Dialect dialect) {
  return Builder(t, features, evaluation, m, dialect).build();
}

ThermalTestPiecePlan planThermalTestPiece(const ThermalTestPiece& t, const parts::Machine& m, parts::Dialect dialect) {
  return planThermalTestPiece(t, parts::nominalFeatures(t), parts::thermalTestPieceEvaluation(), m, dialect);
}

void checkThermalTestPiecePrograms(const ThermalTestPiece& t, const parts::Machine& m,
                                   const std::vector<NotedProgram>& programs) {
  if (!m.c.present)
    throw InputError(m.file, 0, "axes.C: the thermal test piece needs a rotary table (C axis); " + m.name + " has none");
  const Envelope env(t);
  const Collisions col{env, parts::partOriginOnMachine(t, m.c_axis_centre_mm, m.table_surface_z_mm), m.c.positive_is_clockwise};
  ProgramWalker walker(m, walkerTools(t));
  for (const auto& p : programs) {
    const bool finished = p.role != "pre_machining";
    walker.setCheck([&col, finished](const Motion& mo) { col.check(mo, finished); });
    walker.run(p);
  }
}

std::string ttpProgramText(const NotedProgram& p, parts::Dialect dialect) {
  return programText(p, dialect);
}

}  // namespace probeloop::planner
