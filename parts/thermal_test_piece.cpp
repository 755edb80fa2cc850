#include "parts/thermal_test_piece.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::parts {

using Eigen::Vector2d;
using Eigen::Vector3d;

const CuttingTool* ThermalTestPiece::tool(int number) const {
  for (const auto& t : tools)
    if (t.number == number) return &t;
  return nullptr;
}

namespace {

Vector2d point2(YamlMap& m, const std::string& key) {
  const auto v = m.quantityList(key, Dimension::Length);
  if (v.size() != 2) m.fail(key, "expected [x, y]");
  return {v[0], v[1]};
}

int toolNumber(YamlMap& m, const ThermalTestPiece& t, const std::string& key = "tool") {
  const int n = m.integer(key);
  if (!t.tool(n)) m.fail(key, "tool T" + std::to_string(n) + " is not in the tools list");
  return n;
}

std::vector<double> lengths(YamlMap& m, const std::string& key) {
  auto v = m.quantityList(key, Dimension::Length);
  if (v.empty()) m.fail(key, "expected a non-empty list of lengths");
  return v;
}

double wrap360(double a) {
  a = std::fmod(a, 360.0);
  return a < 0 ? a + 360.0 : a;
}

// Half extent of facet `angle` along its face, clipped by the two notches of its segment:
// the face runs from the centre a (cos, sin) along u = (-sin, cos) until the neighbouring
// facet (a tan(pitch/2)) or the notch flank (|y| = w_x/2) or the Y notch (|x| = w_y/2).
double clippedHalfWidth(const ThermalTestPiece& t, double angle_deg) {
  const double a = t.facet_apothem_mm, th = degToRad(angle_deg);
  const Vector2d c(a * std::cos(th), a * std::sin(th)), u(-std::sin(th), std::cos(th));
  double half = a * std::tan(degToRad(t.facet_pitch_deg / 2));
  for (double s : {-1.0, 1.0}) {
    // Walk from the centre along s*u; stop where |y| falls to w_x/2 or |x| to w_y/2.
    const Vector2d d = s * u;
    auto limit = [&](double coord, double dir, double bound) {
      // coord + k dir reaches +-bound moving toward the axis.
      if (std::fabs(dir) < 1e-12) return;
      const double target = coord > 0 ? bound : -bound;
      const double k = (target - coord) / dir;
      if (k > 0) half = std::min(half, k);
    };
    limit(c.y(), d.y(), t.x_notch_width_mm / 2);
    limit(c.x(), d.x(), t.y_notch_width_mm / 2);
  }
  return half;
}

}  // namespace

ThermalTestPiece loadThermalTestPiece(const std::string& path) {
  YamlMap root(loadYamlFile(path), path, "");
  root.choice("kind", {"thermal_test_piece"});
  ThermalTestPiece t;
  t.file = path;
  t.name = root.stringOr("name", "thermal test piece");

  YamlMap b = root.map("blank");
  t.blank_diameter_mm = b.positiveQuantity("diameter", Dimension::Length);
  t.blank_height_mm = b.positiveQuantity("height", Dimension::Length);
  t.material = readMaterial(b.map("material"));
  YamlMap bh = b.map("bolt_holes");
  t.bolt_holes = bh.integer("count");
  t.bolt_circle_diameter_mm = bh.positiveQuantity("circle_diameter", Dimension::Length);
  t.bolt_first_angle_deg = bh.quantity("first_angle", Dimension::Angle);
  t.bolt_hole_diameter_mm = bh.positiveQuantity("diameter", Dimension::Length);
  t.bolt_hole_depth_mm = bh.positiveQuantity("depth", Dimension::Length);
  if (t.bolt_holes < 0 || t.bolt_holes > 12) bh.fail("count", "expected 0..12 holes");
  bh.finish();
  b.finish();

  YamlMap fx = root.map("fixture");
  YamlMap ad = fx.map("adapter");
  t.adapter_diameter_mm = ad.positiveQuantity("diameter", Dimension::Length);
  t.adapter_height_mm = ad.positiveQuantity("height", Dimension::Length);
  ad.finish();
  YamlMap wa = fx.map("washers");
  t.washer_diameter_mm = wa.positiveQuantity("diameter", Dimension::Length);
  t.washer_thickness_mm = wa.positiveQuantity("thickness", Dimension::Length);
  wa.finish();
  fx.finish();

  t.tools = readCuttingTools(root, "tools");

  YamlMap pre = root.map("pre_machining");
  t.pre_spindle_rpm = pre.positiveQuantity("spindle_speed", Dimension::RotSpeed);
  t.pre_feed_mm_per_min = pre.positiveQuantity("feed", Dimension::Feed);
  t.pre_machining_coolant = pre.boolean("coolant");
  YamlMap face = pre.map("face");
  t.face_tool = toolNumber(face, t);
  t.face_depth_mm = face.positiveQuantity("depth", Dimension::Length);
  t.face_stepover_mm = face.positiveQuantity("stepover", Dimension::Length);
  t.face_feed_mm_per_min = face.positiveQuantity("feed", Dimension::Feed);
  if (!(t.face_depth_mm < t.blank_height_mm)) face.fail("depth", "must be less than the blank height");
  if (!(t.face_stepover_mm < t.tool(t.face_tool)->diameter_mm))
    face.fail("stepover", "must be less than the tool diameter, or ridges stay between the passes");
  face.finish();
  const double H = t.finishedHeight();
  YamlMap bands = pre.map("bands");
  t.band_tool = toolNumber(bands, t);
  t.band_feed_mm_per_min = bands.positiveQuantity("feed", Dimension::Feed);
  for (auto& bm : bands.mapList("list")) {
    TtpBand band;
    band.diameter_mm = bm.positiveQuantity("diameter", Dimension::Length);
    band.z_from_mm = bm.quantity("z_from", Dimension::Length);
    band.z_to_mm = bm.quantity("z_to", Dimension::Length);
    if (!(band.diameter_mm < t.blank_diameter_mm)) bm.fail("diameter", "must be smaller than the blank diameter");
    if (!(band.z_from_mm < band.z_to_mm)) bm.fail("z_to", "must be above z_from");
    if (band.z_from_mm < -H - 1e-9 || band.z_to_mm > 1e-9)
      bm.fail("z_from", "a band must lie between the bottom (z = -" + formatNumber(H) + ") and the finished top (z = 0)");
    for (const auto& o : t.bands)
      if (band.z_from_mm < o.z_to_mm - 1e-9 && o.z_from_mm < band.z_to_mm - 1e-9)
        bm.fail("z_from", "bands overlap in z");
    bm.finish();
    t.bands.push_back(band);
  }
  bands.finish();
  YamlMap mark = pre.map("mark");
  t.mark_tool = toolNumber(mark, t);
  t.mark_from_mm = point2(mark, "from");
  t.mark_to_mm = point2(mark, "to");
  t.mark_depth_mm = mark.positiveQuantity("depth", Dimension::Length);
  mark.finish();
  YamlMap yn = pre.map("y_notch");
  t.y_notch_tool = toolNumber(yn, t);
  t.y_notch_width_mm = yn.positiveQuantity("width", Dimension::Length);
  t.y_notch_depth_mm = yn.positiveQuantity("depth", Dimension::Length);
  t.y_notch_step_mm = yn.positiveQuantity("step", Dimension::Length);
  if (!(t.tool(t.y_notch_tool)->diameter_mm <= t.y_notch_width_mm)) yn.fail("width", "the tool is wider than the notch");
  if (!(t.y_notch_depth_mm < H)) yn.fail("depth", "must be less than the finished height");
  yn.finish();
  YamlMap xn = pre.map("x_notch");
  t.x_notch_tool = toolNumber(xn, t);
  t.x_notch_width_mm = xn.positiveQuantity("width", Dimension::Length);
  t.x_notch_depth_mm = xn.positiveQuantity("depth", Dimension::Length);
  t.x_notch_step_mm = xn.positiveQuantity("step", Dimension::Length);
  t.x_notch_allowance_mm = xn.quantity("finishing_allowance", Dimension::Length);
  if (!(t.x_notch_depth_mm < H)) xn.fail("depth", "must be less than the finished height");
  if (t.x_notch_allowance_mm < 0) xn.fail("finishing_allowance", "must not be negative");
  xn.finish();
  YamlMap fa = pre.map("facets");
  t.facet_pre_tool = toolNumber(fa, t);
  t.facets_per_segment = fa.integer("per_segment");
  t.facet_pitch_deg = fa.positiveQuantity("pitch", Dimension::Angle);
  t.facet_apothem_mm = fa.positiveQuantity("apothem", Dimension::Length);
  t.facet_allowance_mm = fa.positiveQuantity("allowance", Dimension::Length);
  t.first_normal_angle_deg = fa.quantity("first_normal_angle", Dimension::Angle);
  if (t.facets_per_segment < 2) fa.fail("per_segment", "at least a reference and one measurement facet");
  {
    const double last = t.first_normal_angle_deg + (t.facets_per_segment - 1) * t.facet_pitch_deg;
    if (!(t.first_normal_angle_deg > 0 && last < 90))
      fa.fail("first_normal_angle", "the facets of segment X1 must face into the +X+Y quadrant (0..90 deg); the last is at " +
                                        formatNumber(last) + " deg");
  }
  for (const auto& band : t.bands)
    if (band.z_to_mm > t.notchFloorZ() + 1e-9 && !(band.diameter_mm / 2 > t.facet_apothem_mm + t.facet_allowance_mm))
      fa.fail("apothem", "the facets must cut into the band d" + formatNumber(band.diameter_mm) + " above the notch floor");
  fa.finish();
  pre.finish();

  YamlMap te = root.map("test");
  t.test_tool = toolNumber(te, t);
  t.test_spindle_rpm = te.positiveQuantity("spindle_speed", Dimension::RotSpeed);
  t.test_feed_mm_per_min = te.positiveQuantity("feed", Dimension::Feed);
  t.test_coolant = te.boolean("coolant");
  t.cut_depth_mm = te.positiveQuantity("cut_depth", Dimension::Length);
  if (t.cut_depth_mm > t.facet_allowance_mm + 1e-9) te.fail("cut_depth", "must not exceed the facets' allowance");
  YamlMap zp = te.map("z_paths");
  t.z_paths = zp.integer("count");
  t.z_path_pitch_mm = zp.positiveQuantity("pitch", Dimension::Length);
  t.z_path_x_from_mm = zp.quantity("x_from", Dimension::Length);
  t.z_path_x_to_mm = zp.quantity("x_to", Dimension::Length);
  if (t.z_paths != t.facets_per_segment)
    zp.fail("count", "one Z path per cutting cycle: must equal pre_machining.facets.per_segment (" +
                         std::to_string(t.facets_per_segment) + ")");
  if (!(t.z_path_x_from_mm < -t.blank_diameter_mm / 2 && t.z_path_x_to_mm > t.blank_diameter_mm / 2))
    zp.fail("x_from", "the Z paths run the whole length of the piece, from outside to outside (|x| > " +
                          formatNumber(t.blank_diameter_mm / 2) + ")");
  {
    // The paths must stay clear of the notch flanks: they are the datum of the CMM X axis.
    const double d = t.tool(t.test_tool)->diameter_mm;
    const double span = (t.z_paths - 1) * t.z_path_pitch_mm + d;
    if (!(span < t.x_notch_width_mm - 1e-9))
      zp.fail("pitch", std::to_string(t.z_paths) + " Z paths at " + formatNumber(t.z_path_pitch_mm) + " mm pitch cut by the d" +
                           formatNumber(d) + " test tool span " + formatNumber(span) + " mm: they do not fit in the " +
                           formatNumber(t.x_notch_width_mm) +
                           " mm notch without cutting its flanks (the datum of the CMM X direction; docs/thermal-test-piece.md)");
  }
  zp.finish();
  t.facet_path_half_length_mm = te.positiveQuantity("facet_path_half_length", Dimension::Length);
  {
    const YAML::Node o = te.raw("order");
    if (!o.IsSequence()) te.fail("order", "expected a list of path/facet numbers");
    std::set<int> seen;
    for (const auto& item : o) {
      int k = 0;
      try {
        k = item.as<int>();
      } catch (const YAML::Exception&) {
        te.fail("order", "expected whole numbers");
      }
      if (k < 1 || k > t.z_paths || !seen.insert(k).second)
        te.fail("order", "must list each of 1.." + std::to_string(t.z_paths) + " once (found " + std::to_string(k) + ")");
      t.order.push_back(k);
    }
    if (static_cast<int>(t.order.size()) != t.z_paths)
      te.fail("order", "must list each of 1.." + std::to_string(t.z_paths) + " once");
  }
  t.waiting_position_mm = point2(te, "waiting_position");
  t.ring_radius_mm = te.positiveQuantity("ring_radius", Dimension::Length);
  t.wait_s = te.positiveQuantity("wait", Dimension::Duration);
  t.c_turn_move_s = te.positiveQuantity("c_turn_move", Dimension::Duration);
  int load_cycles = 0;
  for (auto& lm : te.mapList("load")) {
    TtpLoadPhase ph;
    ph.name = lm.choice("phase", {"warm_up", "hold"});
    ph.cycles = lm.integer("cycles");
    ph.c_axis_rpm = lm.quantity("c_axis_speed", Dimension::RotSpeed);
    if (ph.cycles < 1) lm.fail("cycles", "must be >= 1");
    if (ph.c_axis_rpm < 0) lm.fail("c_axis_speed", "must not be negative");
    if (ph.name == "hold" && ph.c_axis_rpm != 0) lm.fail("c_axis_speed", "an NC hold keeps the table at C = 0 (0 rpm)");
    load_cycles += ph.cycles;
    lm.finish();
    t.load.push_back(ph);
  }
  if (load_cycles != t.cycles() - 1)
    te.fail("load", "the load phases hold " + std::to_string(load_cycles) + " cutting cycles; after the reference there are " +
                        std::to_string(t.cycles() - 1));
  {
    const double r_max = t.blank_diameter_mm / 2;
    double r_tool = 0;
    for (const auto& c : t.tools) r_tool = std::max(r_tool, c.diameter_mm / 2);
    if (!(t.ring_radius_mm > r_max + r_tool))
      te.fail("ring_radius", "must exceed the blank radius plus the largest tool radius (" + formatNumber(r_max + r_tool) + " mm)");
    if (!(t.waiting_position_mm.norm() > r_max + r_tool))
      te.fail("waiting_position", "must lie outside the blank (radius > " + formatNumber(r_max + r_tool) + " mm)");
  }
  te.finish();

  YamlMap in = root.map("inspection");
  YamlMap pr = in.map("probing");
  t.probing.feed_mm_per_min = pr.positiveQuantity("feed", Dimension::Feed);
  t.probing.positioning_feed_mm_per_min = pr.positiveQuantity("positioning_feed", Dimension::Feed);
  t.probing.approach_mm = pr.positiveQuantity("approach", Dimension::Length);
  t.probing.overtravel_mm = pr.positiveQuantity("overtravel", Dimension::Length);
  t.probing.clearance_mm = pr.positiveQuantity("clearance", Dimension::Length);
  pr.finish();
  YamlMap fp = in.map("facet_points");
  t.facet_points_across_mm = lengths(fp, "across");
  t.facet_points_heights_mm = lengths(fp, "heights");
  for (double h : t.facet_points_heights_mm)
    if (!(h < 0 && h > t.notchFloorZ())) fp.fail("heights", "must lie on the facets, between the notch floor and the top");
  if (t.facet_points_across_mm.size() * t.facet_points_heights_mm.size() < 3)
    fp.fail("across", "a plane needs at least 3 points per facet");
  fp.finish();
  YamlMap zpp = in.map("z_path_points");
  t.z_path_points_along_mm = lengths(zpp, "along");
  t.z_path_points_across_mm = lengths(zpp, "across");
  for (double a : t.z_path_points_across_mm)
    if (!(std::fabs(a) < t.tool(t.test_tool)->diameter_mm / 2)) zpp.fail("across", "must lie within the path's width");
  if (t.z_path_points_along_mm.size() < 2 || t.z_path_points_across_mm.size() < 2)
    zpp.fail("along", "a plane needs points spread along and across the path (at least 2 x 2)");
  zpp.finish();
  YamlMap dc = in.map("datum_circle");
  t.datum_band_diameter_mm = dc.positiveQuantity("band_diameter", Dimension::Length);
  t.datum_circle_z_mm = dc.quantity("z", Dimension::Length);
  t.datum_circle_points = dc.integer("points");
  {
    bool on_band = false;
    for (const auto& band : t.bands)
      if (std::fabs(band.diameter_mm - t.datum_band_diameter_mm) < 1e-9 && t.datum_circle_z_mm > band.z_from_mm &&
          t.datum_circle_z_mm < band.z_to_mm && band.z_to_mm <= std::min(t.notchFloorZ(), -t.y_notch_depth_mm) + 1e-9)
        on_band = true;
    if (!on_band)
      dc.fail("z", "must lie on a listed band that stays whole below both notches (the origin circle, seed 004 L2055)");
  }
  if (t.datum_circle_points < 3) dc.fail("points", "a circle needs at least 3 points");
  dc.finish();
  t.cmm = readCmm(in.map("cmm"));
  YamlMap om = in.map("on_machine");
  t.on_machine_repeatability_um = om.quantity("repeatability", Dimension::Micrometre);
  t.on_machine_temperature_change_K = om.quantity("temperature_change", Dimension::Temperature);
  if (t.on_machine_repeatability_um < 0) om.fail("repeatability", "must not be negative");
  if (t.on_machine_temperature_change_K < 0) om.fail("temperature_change", "must not be negative");
  om.finish();
  in.finish();

  YamlMap ev = root.map("evaluation");
  t.eq_7_10_alpha_um_per_m_K = ev.number("alpha_um_per_m_K");
  t.alpha_u_um_per_m_K = ev.number("alpha_u_um_per_m_K");
  t.eq_7_10_radius_mm = ev.positiveQuantity("radius", Dimension::Length);
  if (!(t.eq_7_10_alpha_um_per_m_K > 0)) ev.fail("alpha_um_per_m_K", "must be positive");
  if (t.alpha_u_um_per_m_K < 0) ev.fail("alpha_u_um_per_m_K", "must not be negative");
  ev.finish();
  root.finish();

  // Every measurement point must lie on its facet: the clipped facets are narrower.
  for (int s = 0; s < 4; ++s)
    for (int k = 1; k <= t.facets_per_segment; ++k) {
      const double half = clippedHalfWidth(t, facetNormalAngle(t, static_cast<FacetSide>(s), k));
      for (double a : t.facet_points_across_mm)
        if (std::fabs(a) > half - 0.5)
          throw InputError(path, 0, "inspection.facet_points.across: " + formatNumber(a) + " mm lies within 0.5 mm of the edge of facet " +
                                        facetId(static_cast<FacetSide>(s), k) + " (half width " + formatNumber(half, 2) +
                                        " mm between the notches)");
    }
  return t;
}

// --- geometry -------------------------------------------------------------------------

const char* facetSideName(FacetSide s) {
  static const char* names[] = {"X1", "Y1", "X2", "Y2"};
  return names[static_cast<int>(s)];
}

std::string zPathId(int j) { return "Z" + std::to_string(j); }
std::string facetId(FacetSide side, int k) { return std::string(facetSideName(side)) + "_" + std::to_string(k); }

double facetNormalAngle(const ThermalTestPiece& t, FacetSide side, int k) {
  const double phi = t.first_normal_angle_deg + (k - 1) * t.facet_pitch_deg;
  switch (side) {
    case FacetSide::X1: return wrap360(phi);
    case FacetSide::Y1: return wrap360(180 - phi);  // mirror of X1 about the Y axis
    case FacetSide::X2: return wrap360(phi + 180);  // opposite of X1
    case FacetSide::Y2: return wrap360(-phi);       // opposite of Y1
  }
  return phi;
}

double zPathY(const ThermalTestPiece& t, int j) { return (j - (t.z_paths + 1) / 2.0) * t.z_path_pitch_mm; }

std::vector<NominalFeature> nominalFeatures(const ThermalTestPiece& t) {
  std::vector<NominalFeature> out;
  const double R = t.blank_diameter_mm / 2, floor = t.notchFloorZ(), cut = t.cuttingZ();
  const double a = t.facet_apothem_mm;
  const double flank_x = std::sqrt(std::max(0.0, a * a - std::pow(t.x_notch_width_mm / 2, 2)));
  auto plane = [](std::string id, std::string role, std::string group, int index, Vector3d p, Vector3d n, Vector3d u,
                  double hu, double hv) {
    NominalFeature f;
    f.id = std::move(id);
    f.kind = "plane";
    f.role = std::move(role);
    f.group = std::move(group);
    f.index = index;
    f.point_mm = p;
    f.direction = n;
    f.u = u;
    f.half_u_mm = hu;
    f.half_v_mm = hv;
    return f;
  };
  // The finished top is no wider than the band that reaches z = 0.
  double r_top = R;
  for (const auto& band : t.bands)
    if (band.z_to_mm >= -1e-9) r_top = band.diameter_mm / 2;
  out.push_back(plane("TOP", "datum_top", "datum", 0, Vector3d::Zero(), Vector3d::UnitZ(), Vector3d::UnitX(), r_top, r_top));
  out.push_back(plane("FLANK_P", "datum_flank", "datum", 0, Vector3d(0, t.x_notch_width_mm / 2, floor / 2), -Vector3d::UnitY(),
                      Vector3d::UnitX(), flank_x, -floor / 2));
  out.push_back(plane("FLANK_N", "datum_flank", "datum", 0, Vector3d(0, -t.x_notch_width_mm / 2, floor / 2), Vector3d::UnitY(),
                      Vector3d::UnitX(), flank_x, -floor / 2));
  for (const auto& band : t.bands)
    if (std::fabs(band.diameter_mm - t.datum_band_diameter_mm) < 1e-9) {
      NominalFeature c;
      c.id = "CYL";
      c.kind = "cylinder";
      c.role = "datum_circle";
      c.group = "datum";
      c.point_mm = Vector3d(0, 0, (band.z_from_mm + band.z_to_mm) / 2);
      c.direction = Vector3d::UnitZ();
      c.radius_mm = band.diameter_mm / 2;
      c.half_v_mm = (band.z_to_mm - band.z_from_mm) / 2;
      out.push_back(c);
    }
  const double r_test = t.tool(t.test_tool)->diameter_mm / 2;
  for (int j = 1; j <= t.z_paths; ++j) {
    const double y = zPathY(t, j);
    // The floor under the path reaches as far as the band below it.
    double r_floor = R;
    for (const auto& band : t.bands)
      if (band.z_from_mm <= floor && band.z_to_mm >= floor) r_floor = band.diameter_mm / 2;
    const double hu = std::sqrt(std::max(0.0, r_floor * r_floor - std::pow(std::fabs(y) + r_test, 2)));
    out.push_back(plane(zPathId(j), "z_path", "Z", j, Vector3d(0, y, cut), Vector3d::UnitZ(), Vector3d::UnitX(), hu, r_test));
  }
  for (int s = 0; s < 4; ++s)
    for (int k = 1; k <= t.facets_per_segment; ++k) {
      const auto side = static_cast<FacetSide>(s);
      const double ang = facetNormalAngle(t, side, k), th = degToRad(ang);
      NominalFeature f = plane(facetId(side, k), "facet", facetSideName(side), k,
                               Vector3d(a * std::cos(th), a * std::sin(th), cut / 2), Vector3d(std::cos(th), std::sin(th), 0),
                               Vector3d(-std::sin(th), std::cos(th), 0), clippedHalfWidth(t, ang), -cut / 2);
      f.angle_deg = ang;
      out.push_back(f);
    }
  return out;
}

std::vector<TtpCuttingCycle> cuttingCycles(const ThermalTestPiece& t) {
  std::vector<TtpCuttingCycle> out;
  TtpCuttingCycle ref;
  ref.cycle = 0;
  ref.z_path = ref.facet = t.order.front();
  ref.phase = "reference";
  out.push_back(ref);
  int c = 1;
  for (const auto& ph : t.load)
    for (int i = 0; i < ph.cycles; ++i, ++c) {
      TtpCuttingCycle x;
      x.cycle = c;
      x.z_path = x.facet = t.order[static_cast<std::size_t>(c)];
      x.phase = ph.name;
      x.c_axis_rpm_before = ph.c_axis_rpm;
      x.nominal_time_s = c * t.wait_s;
      out.push_back(x);
    }
  return out;
}

Workpiece thermalTestPieceWorkpiece(const ThermalTestPiece& t) {
  Workpiece w;
  w.file = t.file;
  w.name = t.name;
  const double R = t.blank_diameter_mm / 2, H = t.finishedHeight();
  w.stock_min_mm = Vector3d(-R, -R, -H);
  w.stock_max_mm = Vector3d(R, R, t.face_depth_mm);
  w.cylindrical = true;
  const double rb = t.bolt_circle_diameter_mm / 2;
  for (int i = 0; i < t.bolt_holes; ++i) {
    const double th = degToRad(t.bolt_first_angle_deg + 360.0 * i / t.bolt_holes);
    const Vector2d c(rb * std::cos(th), rb * std::sin(th));
    w.holes.push_back({c, t.bolt_hole_diameter_mm / 2, -H - 1, -H + t.bolt_hole_depth_mm, "bolt hole " + std::to_string(i + 1)});
    w.obstacles.push_back({c, t.washer_diameter_mm / 2, -H - t.washer_thickness_mm, -H, "washer " + std::to_string(i + 1)});
  }
  w.obstacles.push_back({Vector2d::Zero(), t.adapter_diameter_mm / 2, -H - t.washer_thickness_mm - t.adapter_height_mm,
                         -H - t.washer_thickness_mm, "adapter"});
  w.support_height_mm = t.supportHeight();
  w.material = t.material;
  w.tools = t.tools;
  w.cmm = t.cmm;
  return w;
}

Vector3d partOriginOnMachine(const ThermalTestPiece& t, const Vector2d& c_axis_centre_mm, double table_surface_z_mm) {
  return Vector3d(c_axis_centre_mm.x(), c_axis_centre_mm.y(),
                  table_surface_z_mm + t.adapter_height_mm + t.washer_thickness_mm + t.finishedHeight());
}

// --- evaluation formulas ----------------------------------------------------------------

TtpErrors ttpErrors(const TtpMeasures& i, const TtpMeasures& r) {
  TtpErrors e;
  const double dX1 = i.d_X1_mm - r.d_X1_mm, dX2 = i.d_X2_mm - r.d_X2_mm;
  const double dY1 = i.d_Y1_mm - r.d_Y1_mm, dY2 = i.d_Y2_mm - r.d_Y2_mm;
  e.EX_um = (dX2 - dX1) / 2 * 1e3;  // seed 004 Eq. 7.1, "+ d_X1(t0)" (notes §11 item 10)
  e.EY_um = (dY2 - dY1) / 2 * 1e3;  // seed 004 Eq. 7.2, likewise
  e.EX_printed_um = (i.d_X2_mm - r.d_X2_mm - i.d_X1_mm - r.d_X1_mm) / 2 * 1e3;  // Eq. 7.1 as printed
  e.EY_printed_um = (i.d_Y2_mm - r.d_Y2_mm - i.d_Y1_mm - r.d_Y1_mm) / 2 * 1e3;  // Eq. 7.2 as printed
  e.ETTP_7_3_um = ((dX1 + dX2) + (dY1 + dY2)) / 2 * 1e3;  // seed 004 Eq. 7.3: l = d1 + d2
  e.ETTP_7_9_um = (dX1 + dX2 + dY1 + dY2) / 4 * 1e3;      // seed 004 Eq. 7.9 with g = d(ti) - d(t0)
  e.EZ_um = (i.d_Z_mm - r.d_Z_mm) * 1e3;                  // seed 004 Eq. 7.4
  e.EB_urad = i.beta_urad - r.beta_urad;                  // seed 004 Eq. 7.5
  return e;
}

GaugeErrors gaugeErrors(double gX1, double gX2, double gY1, double gY2) {
  GaugeErrors e;
  e.EX_um = (gX2 - gX1) / 2;                  // seed 004 Eq. 7.7
  e.EY_um = (gY2 - gY1) / 2;                  // seed 004 Eq. 7.8
  e.ETTP_um = (gY2 + gY1 + gX2 + gX1) / 4;    // seed 004 Eq. 7.9
  return e;
}

double measurementDeviationEq76_um(double alpha_um_per_m_K, double dT_K, double E_um) {
  return alpha_um_per_m_K * 1e-6 * dT_K * E_um;  // seed 004 Eq. 7.6
}

double temperatureEquivalentEq710_K(double E_um, double alpha_um_per_m_K, double R_mm) {
  return E_um / (alpha_um_per_m_K * R_mm * 1e-3);  // seed 004 Eq. 7.10
}

double span(const std::vector<double>& v) {
  if (v.empty()) return 0;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return *hi - *lo;
}

double spanReductionPercent(double uc, double c) {
  if (!(std::fabs(uc) > 0)) throw GeometryError("a reduction needs a non-zero uncompensated span");
  return (uc - c) / uc * 100;
}

}  // namespace probeloop::parts
