#include "planner/thermal_test_piece.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "parts/piece_kinds.hpp"
#include "planner/angles.hpp"
#include "planner/piece_manifest.hpp"

namespace probeloop::planner {

using Eigen::Vector2d;
using Eigen::Vector3d;
using parts::FacetSide;
using parts::ThermalTestPiece;

namespace {

// A tool's edge keeps this far outside the blank where passes start and end, and on the chords
// of the ring (our choice: the description states only the ring).
constexpr double kOutside = 2.0;
// The longest step along the ring, so that it looks like one and stays well outside.
constexpr double kMaxRingStepDeg = 30.0;
// The most whole turns one C feed move of the load may command (8-digit C words).
constexpr int kMaxTurnsPerMove = 277;
// Z-path inspection points keep this far from the strips the test's facet cuts sweep over the
// notch floor (as the loader keeps facet points from a facet's edge; docs §5).
constexpr double kStripMargin = 0.5;

// --- 2D geometry of the finished part (collision checks) -------------------------------

using Poly = std::vector<Vector2d>;

// Sutherland-Hodgman: the part of convex polygon P with n . p <= d.
Poly clip(const Poly& P, const Vector2d& n, double d) {
  Poly out;
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Vector2d& a = P[i];
    const Vector2d& b = P[(i + 1) % P.size()];
    const double fa = n.dot(a) - d, fb = n.dot(b) - d;
    if (fa <= 0) out.push_back(a);
    if ((fa < 0 && fb > 0) || (fa > 0 && fb < 0)) out.push_back(a + (b - a) * (fa / (fa - fb)));
  }
  return out;
}

double pointSegment(const Vector2d& p, const Vector2d& a, const Vector2d& b) {
  const Vector2d ab = b - a;
  const double L2 = ab.squaredNorm();
  const double s = L2 > 0 ? std::clamp((p - a).dot(ab) / L2, 0.0, 1.0) : 0.0;
  return (p - (a + s * ab)).norm();
}

double cross(const Vector2d& a, const Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

bool segmentsCross(const Vector2d& a, const Vector2d& b, const Vector2d& c, const Vector2d& d) {
  const double d1 = cross(b - a, c - a), d2 = cross(b - a, d - a), d3 = cross(d - c, a - c), d4 = cross(d - c, b - c);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0));
}

bool insideConvex(const Poly& P, const Vector2d& p) {
  // Counterclockwise polygon: inside = left of every edge.
  for (std::size_t i = 0; i < P.size(); ++i)
    if (cross(P[(i + 1) % P.size()] - P[i], p - P[i]) < 0) return false;
  return true;
}

double segmentPolygon(const Vector2d& a, const Vector2d& b, const Poly& P) {
  if (P.size() < 3) return INFINITY;
  if (insideConvex(P, a) || insideConvex(P, b)) return 0;
  double d = INFINITY;
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Vector2d& c = P[i];
    const Vector2d& e = P[(i + 1) % P.size()];
    if (segmentsCross(a, b, c, e)) return 0;
    d = std::min({d, pointSegment(a, c, e), pointSegment(b, c, e), pointSegment(c, a, b), pointSegment(e, a, b)});
  }
  return d;
}

double segmentOrigin(const Vector2d& a, const Vector2d& b) { return pointSegment(Vector2d::Zero(), a, b); }

// What stands on the table, in the part frame: the blank's cylinder (pre-machining, and below
// the notch floor afterwards), above the floor the four segments with their facets at the
// pre-machining allowance (a superset of the part at any later time), the fixture below.
struct Envelope {
  double R = 0, H = 0, blank_top = 0, floor = 0, fixture_r = 0;
  std::vector<Poly> segments;
  double segments_r = 0;  // farthest point of a segment from the axis

  explicit Envelope(const ThermalTestPiece& t) {
    R = t.blank_diameter_mm / 2;
    H = t.finishedHeight();
    blank_top = t.face_depth_mm;
    floor = t.notchFloorZ();
    fixture_r = std::max(t.adapter_diameter_mm / 2, (t.bolt_circle_diameter_mm + t.washer_diameter_mm) / 2);
    // A 360-gon around the blank's circle, clipped by the notches and the facets.
    Poly circle;
    const double rc = R / std::cos(kPi / 360);
    for (int i = 0; i < 360; ++i) circle.emplace_back(rc * std::cos(degToRad(i + 0.5)), rc * std::sin(degToRad(i + 0.5)));
    const FacetSide sides[4] = {FacetSide::X1, FacetSide::Y1, FacetSide::X2, FacetSide::Y2};
    const double sx[4] = {1, -1, -1, 1}, sy[4] = {1, 1, -1, -1};
    for (int s = 0; s < 4; ++s) {
      Poly P = clip(circle, Vector2d(0, -sy[s]), -t.x_notch_width_mm / 2);
      P = clip(P, Vector2d(-sx[s], 0), -t.y_notch_width_mm / 2);
      for (int k = 1; k <= t.facets_per_segment; ++k) {
        const double a = degToRad(parts::facetNormalAngle(t, sides[s], k));
        P = clip(P, Vector2d(std::cos(a), std::sin(a)), t.facet_apothem_mm + t.facet_allowance_mm);
      }
      for (const auto& v : P) segments_r = std::max(segments_r, v.norm());
      segments.push_back(P);
    }
  }
  double top(bool finished) const { return finished ? 0.0 : blank_top; }
};

std::string xyz(const Vector3d& v) {
  return "X" + formatNumber(v.x(), 3) + " Y" + formatNumber(v.y(), 3) + " Z" + formatNumber(v.z(), 3);
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

// The collision rules of docs/thermal-test-piece.md §5 for every motion the walker is about to
// make (SafetyError "<program>: <where>: ..."). `finished`: after pre-machining, when the
// notches and the facets (at their allowance) have opened the part.
struct Collisions {
  const Envelope& env;
  Vector3d O;  // part origin, machine tip coordinates at C = 0
  bool cw;     // +C turns the table clockwise (C')

  void check(const Motion& mo, bool finished) const {
    const std::string tool = mo.tool.probe ? "probe" : "tool T" + std::to_string(mo.tool.number);
    auto fail = [&](const std::string& m) { throw SafetyError(*mo.program + ": " + mo.note->where + ": " + m); };
    const Vector3d qa = mo.from_tip - O, qb = mo.to_tip - O;
    if (!qa.allFinite() || !qb.allFinite() || !std::isfinite(mo.from_c) || !std::isfinite(mo.to_c))
      fail(std::string(mo.what) + " to a position that is not a finite number");
    const double rho = mo.tool.radius_mm;
    const double below = mo.tool.probe ? rho : 0.0;  // lowest point of the tool under its tip coordinate
    const double top = env.top(finished);
    // Below the top a G0 moves one axis at a time: a G0 of several axes may dog-leg (Fanuc
    // non-linear positioning), so such moves are G1 (docs §5).
    if (mo.kind == MotionKind::Rapid && std::min(qa.z(), qb.z()) - below < top - 1e-9) {
      int axes = 0;
      // (1 um: a retract starts at the unrounded contact, its target is rounded to 0.1 um.)
      for (int i = 0; i < 3; ++i) axes += std::fabs(qa(i) - qb(i)) > 1e-3;
      if (axes > 1)
        fail("G0 from " + xyz(mo.from_tip) + " to " + xyz(mo.to_tip) + " moves " + std::to_string(axes) +
             " axes with the " + tool + " below the top of the part (a G0 may dog-leg: only G1 there)");
    }
    // Cuts and measuring moves are meant to touch the part; a retract leaves a contact straight
    // back along the approach line, which the protected move came down clear of.
    if (mo.note->cut || mo.note->retract || mo.kind == MotionKind::Measuring) return;
    if (mo.kind == MotionKind::CIndex || mo.kind == MotionKind::CFeed) {
      if (mo.from_c == mo.to_c) return;
      const double zb = qa.z() - below;
      if (zb >= top - 1e-9) return;
      const double r = qa.head<2>().norm();
      double need = finished && zb >= env.floor - 1e-9 ? env.segments_r + rho : env.R + rho;
      if (zb < -env.H - 1e-9) need = std::max(need, env.fixture_r + rho);
      if (r < need - 1e-9)
        fail(std::string(mo.what) + " turns C from " + formatNumber(mo.from_c, 3) + " to " + formatNumber(mo.to_c, 3) +
             " deg with the " + tool + " at " + xyz(mo.from_tip) + ", " + formatNumber(r, 3) +
             " mm from the C axis: inside the circle the part sweeps (needs " + formatNumber(need, 3) + " mm, or the " + tool +
             " above the part)");
      return;
    }
    // Straight up: the part only narrows upward (bands step in, notches and facets open
    // upward), so a tool rising from where it stands meets nothing.
    if ((qa.head<2>() - qb.head<2>()).norm() < 1e-9 && qb.z() >= qa.z()) return;
    const double zb = std::min(qa.z(), qb.z()) - below;
    if (zb >= top - 1e-9) return;
    const Vector2d pa = parts::unturnedByTable(qa.head<2>(), mo.from_c, cw),
                   pb = parts::unturnedByTable(qb.head<2>(), mo.from_c, cw);  // part frame
    const double d_axis = segmentOrigin(pa, pb);
    double need = env.R + rho;
    if (zb < -env.H - 1e-9) need = std::max(need, env.fixture_r + rho);
    if (d_axis >= need - 1e-9) return;
    double d_part = 0;
    if (finished && zb >= env.floor - 1e-9) {
      d_part = INFINITY;
      for (const auto& s : env.segments) d_part = std::min(d_part, segmentPolygon(pa, pb, s));
      if (d_part >= rho - 1e-9) return;
    }
    fail(std::string(mo.what) + " from " + xyz(mo.from_tip) + " to " + xyz(mo.to_tip) + " at C " + formatNumber(mo.from_c, 3) +
         " would take the " + tool + " through the part: it comes " + formatNumber(d_axis, 3) +
         " mm near the C axis below the top (needs " + formatNumber(need, 3) + " mm outside the blank" +
         (finished ? ", or " + formatNumber(rho, 3) + " mm clear of the segments above the notch floor" : "") + ")");
  }
};

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

class Builder {
 public:
  Builder(const ThermalTestPiece& t, const std::vector<parts::NominalFeature>& features,
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

  ThermalTestPiecePlan build() {
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

 private:
  // --- the layout ---------------------------------------------------------------------------
  const parts::NominalFeature& feature(const std::string& id) const {
    for (const auto& f : features_)
      if (f.id == id) return f;
    throw std::logic_error("thermal test piece: the features handed to the planner lack " + id);
  }

  // The description's layout must leave every surface the programs cut and probe: an
  // InputError naming the key, never a NaN in a program (docs/thermal-test-piece.md §5).
  void checkLayout() const {
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

  // The TOP points of the +X+Y segment (mirrored into the others): two on the circle a - 2 r_tip
  // at 30 % and 70 % of the segment's angle between the notches (2 r_tip clear of both), one
  // 2 r_tip outside the notch corner on the middle angle. InputError when the notches leave no
  // room for them.
  std::array<Vector2d, 3> topPoints() const {
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

  // --- program building ----------------------------------------------------------------
  NotedProgram& P() { return programs_.back(); }
  void add(gcode::Op op, const std::string& where, bool cut = false, int cut_index = -1) {
    OpNote n;
    n.where = where;
    n.cut = cut;
    n.cut_index = cut_index;
    add(std::move(op), std::move(n));
  }
  void add(gcode::Op op, OpNote n) {
    // Whether the spindle stands at the tool-change height (no second retract before a change).
    if (std::holds_alternative<gcode::RapidMachineZ>(op)) at_tool_change_z_ = true;
    if (std::holds_alternative<gcode::Rapid>(op) || std::holds_alternative<gcode::Feed>(op) ||
        std::holds_alternative<gcode::ProtectedMove>(op) || std::holds_alternative<gcode::ProbeMove>(op))
      at_tool_change_z_ = false;
    P().add(std::move(op), std::move(n));
  }
  double radius(int tool) const { return t_.tool(tool)->diameter_mm / 2; }
  // Machine coordinates (rounded as written) of a point given relative to the C axis at the
  // height of the part origin: q = machine - origin.
  double mx(double qx) const { return round4(O_.x() + qx); }
  double my(double qy) const { return round4(O_.y() + qy); }
  double mz(double z) const { return round4(O_.z() + z); }
  Vector3d mach(double qx, double qy, double z) const { return {mx(qx), my(qy), mz(z)}; }

  void rapidXY(double qx, double qy, const std::string& w) { add(gcode::Rapid{mx(qx), my(qy), std::nullopt}, w); pos_ = {qx, qy}; }
  void rapidZ(double z, const std::string& w) { add(gcode::Rapid{std::nullopt, std::nullopt, mz(z)}, w); }
  void feedXY(double qx, double qy, double F, const std::string& w, bool cut = false, int ci = -1) {
    std::optional<double> x, y;
    if (std::fabs(qx - pos_.x()) > 1e-12) x = mx(qx);
    if (std::fabs(qy - pos_.y()) > 1e-12) y = my(qy);
    if (!x && !y) return;
    add(gcode::Feed{x, y, std::nullopt, round3(F)}, w, cut, ci);
    pos_ = {qx, qy};
  }
  void feedZ(double z, double F, const std::string& w, bool cut = false) {
    add(gcode::Feed{std::nullopt, std::nullopt, mz(z), round3(F)}, w, cut);
  }
  void indexC(double c, const std::string& w) {
    checkCResolution(c, w);
    add(gcode::RotateC{round3(c)}, w);
  }
  void checkCResolution(double c, const std::string& w) const {
    const double steps = c / m_.c.resolution_deg;
    if (std::fabs(steps - std::round(steps)) > 1e-6)
      throw InputError(t_.file, 0, w + ": C " + formatNumber(c, 6) + " deg is not a multiple of the C resolution " +
                                       formatNumber(m_.c.resolution_deg) + " deg of " + m_.file);
  }
  void toolChange(int tool, const std::string& w) {
    if (!at_tool_change_z_) add(gcode::RapidMachineZ{m_.tool_change.z_mm}, w + ": retract to the tool-change height");
    add(gcode::ToolChange{tool, tool != m_.tool_change.empty_tool}, w);
    current_tool_ = tool;
  }
  void spindleOn(double rpm, bool coolant, const std::string& w) {
    add(gcode::Spindle{std::round(rpm)}, w);
    if (coolant) add(gcode::Coolant{true}, w);
    spindle_on_ = true;
  }
  void spindleOff(bool coolant, const std::string& w) {
    if (coolant) add(gcode::Coolant{false}, w);
    add(gcode::Spindle{0}, w);
    spindle_on_ = false;
  }
  // Pre-machining's change to the next step's cutter: nothing when it is in the spindle already,
  // else spindle (and coolant) off, retract, change, spindle on.
  void cutterFor(int tool, const std::string& w) {
    if (tool == current_tool_) return;
    const bool wet = t_.pre_machining_coolant;
    if (spindle_on_) spindleOff(wet, w + ": spindle off");
    toolChange(tool, w + ": tool change");
    spindleOn(t_.pre_spindle_rpm, wet, w + ": spindle on");
  }
  int addCut(const std::string& id, const std::string& feature, int cycle, int tool, double c, const Vector3d& from,
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

  void newProgram(const std::string& role, const std::string& file, int number, const std::string& title) {
    programs_.push_back(newNotedProgram(m_, role, file, number, title));
    current_tool_ = -1;
    spindle_on_ = false;
    P().program.header = {
        "machine: " + m_.name,
        "part: " + t_.name + ", part frame origin at " + xyz(O_) + " [machine, C = 0]",
        "coordinates: G" + std::to_string(53 + m_.work_offset) + " zeroed = machine coordinates of the tool tip with G43",
    };
    // Start from a known state: high, the table level (B) and at C = 0.
    add(gcode::RapidMachineZ{m_.tool_change.z_mm}, "start: retract to the tool-change height");
    if (m_.b.present) add(gcode::RotateB{0}, "start: table level (B 0)");
    add(gcode::RotateC{0}, "start: C 0");
  }
  void toolHeader(std::initializer_list<int> tools) {
    std::vector<int> seen;
    for (int n : tools) {
      if (std::find(seen.begin(), seen.end(), n) != seen.end()) continue;
      seen.push_back(n);
      const auto* c = t_.tool(n);
      P().program.header.push_back("T" + std::to_string(n) + ": " + (c->name.empty() ? c->kind : c->name) + ", d = " +
                                   formatNumber(c->diameter_mm) + " mm, length " + formatNumber(c->length_mm) + " mm");
    }
  }

  // Moves at the current Z below the top of the part go around it: straight when the line
  // keeps the tool `kOutside` outside the blank, else radially out to the ring, along it in
  // chords that stay outside, and radially in (docs/thermal-test-piece.md §5).
  void travel(const Vector2d& to, int tool, const std::string& w) {
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

  // Zig-zag passes across the blank from outside to outside: along Y (lanes in x) or X.
  void passes(bool along_y, const std::vector<double>& lane_list, const std::vector<double>& level_list, int tool, double F,
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

  // --- pre-machining (seed 004 L2002-L2018) ----------------------------------------------
  void preMachining() {
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

  // --- the test (L2022-L2047, docs/thermal-test-piece.md §2) ---------------------------
  void test() {
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

  // The wait before cycle `cy`: the load of its phase (warm-up: C turning; hold: NC hold at C 0).
  void load(const parts::TtpCuttingCycle& cy) {
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

  // --- inspection (L2097-L2101) ---------------------------------------------------------
  struct ProbePoint {
    Vector3d surface, normal;  // part frame
    double c = 0;
  };

  // Adds the manifest point; returns (start, end, contact) in machine coordinates.
  struct Planned {
    Vector3d start, end, contact;
    int index;
  };
  Planned planPoint(const std::string& feature, int position, int point, const ProbePoint& p) {
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
  // Protected move to the start (unless the probe stands there already), measuring move,
  // back to the start.
  void probe(const Planned& p, int position, int point, const std::string& w, bool at_start = false) {
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

  void inspection() {
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

  // --- walking: clock and checks ----------------------------------------------------------
  void walk() {
    ProgramWalker walker(m_, walkerTools(t_));
    const Collisions col{env_, O_, cw_};
    for (std::size_t i = 0; i < programs_.size(); ++i) {
      auto& p = programs_[i];
      const bool finished = p.role != "pre_machining";
      walker.setCheck([&col, finished](const Motion& mo) { col.check(mo, finished); });
      const double t0 = walker.time();
      std::vector<double> before(p.program.ops.size(), NAN), after(p.program.ops.size(), NAN);
      walker.run(p, [&](std::size_t op, double a, double b) {
        before[op] = a;
        after[op] = b;
        const auto& n = p.notes[op];
        if (n.cut_index >= 0) {
          man_.cuts[static_cast<std::size_t>(n.cut_index)].start_s = a;
          man_.cuts[static_cast<std::size_t>(n.cut_index)].end_s = b;
        }
        if (n.point_index >= 0) man_.points[static_cast<std::size_t>(n.point_index)].time_in_cycle_s = b - t0;
      });
      plan_.start_s.push_back(t0);
      plan_.duration_s.push_back(walker.time() - t0);
      plan_.times.push_back(walker.times() - total_);
      total_ = walker.times();
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
  // --- manifest and CMM plan --------------------------------------------------------------
  void manifest() {
    auto& m = man_;
    m.kind = "thermal_test_piece";
    m.dialect = parts::dialectName(dialect_);
    setManifestPrograms(m, programs_, plan_.start_s, plan_.duration_s);
    setManifestMachine(m, m_);
    m.tip_radius_mm = m_.probe.tip_diameter_mm / 2;
    m.probe_repeatability_2sigma_um = m_.probe.repeatability_2sigma_um;
    m.part_name = t_.name;
    m.part_origin_mm = O_;
    m.material_name = t_.material.name;
    m.material_alpha_um_per_m_K = t_.material.alpha_um_per_m_K;
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
    setFeatureCutTimes(m);  // the cycle and the mid time of the cut(s) that finish each feature
    const std::size_t insp = programs_.size() - 1;
    m.cycles = 1;
    m.gap_s = 0;
    m.cycle_time_s = plan_.duration_s[insp];
    m.cycle_start_s = {plan_.start_s[insp]};
  }

  std::string cmmCsv() const {
    return cmmPointsCsv({"probeloop plan: CMM points of " + t_.name + " - nominal surface points and outward unit normals,",
                         "part frame at 20 C (origin on the C axis in the finished top face, X along the large notch), mm"},
                        cmm_);
  }

  const ThermalTestPiece& t_;
  const parts::Machine& m_;
  parts::Dialect dialect_;
  Envelope env_;
  TtpFiles files_;
  Vector3d O_;
  bool cw_ = true;  // +C turns the table clockwise (C')
  double travel_feed_ = 0, clearance_ = 0;
  Vector2d pos_ = Vector2d::Zero();  // current XY relative to the C axis (builder's view)
  bool at_tool_change_z_ = false;
  int current_tool_ = -1;     // in the spindle (builder's view; -1 = unknown at a program's start)
  bool spindle_on_ = false;
  const std::vector<parts::NominalFeature>& features_;
  const std::vector<parts::EvaluationRule>& evaluation_;
  std::vector<parts::TtpCuttingCycle> cycles_;
  std::vector<NotedProgram> programs_;
  std::vector<std::size_t> cycle_first_op_, cycle_last_op_;
  std::vector<CmmRow> cmm_;
  parts::PlanManifest man_;
  ThermalTestPiecePlan plan_;
  WalkTimes total_;
};

}  // namespace

TtpFiles ttpFiles(parts::Dialect d) {
  const std::string ext = d == parts::Dialect::LinuxCnc ? ".ngc" : ".nc";
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
  return dialect == parts::Dialect::LinuxCnc ? gcode::writeLinuxCnc(p.program) : gcode::writeFanucMacroB(p.program);
}

}  // namespace probeloop::planner
