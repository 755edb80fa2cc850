#include "parts/stepped_workpiece.hpp"

#include <algorithm>
#include <cmath>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::parts {

using Eigen::Vector2d;
using Eigen::Vector3d;

const SwExperiment* SteppedWorkpiece::experiment(const std::string& id) const {
  for (const auto& e : experiments)
    if (e.id == id) return &e;
  return nullptr;
}

std::vector<double> SteppedWorkpiece::sizesFor(const SwExperiment& e) const {
  if (e.alternative_sizes) return alternative_sizes_mm;
  std::vector<double> out;
  for (const auto& s : steps) out.push_back(s.size_mm);
  return out;
}

const CuttingTool& SteppedWorkpiece::finishingTool() const {
  for (const auto& t : tools)
    if (t.number == finishing_tool) return t;
  throw std::logic_error("stepped workpiece: finishing tool T" + std::to_string(finishing_tool) + " not in the tools list");
}

// Near the blank's corners, `inset` in from both edges.
std::vector<Vector2d> clampHoleCentres(const SteppedWorkpiece& w) {
  const double c = w.centreXY(), corner = std::min(w.blank_x_mm, w.blank_y_mm) / 2 - w.clamp_hole_inset_mm;
  std::vector<Vector2d> out;
  for (int i = 0; i < w.clamp_holes; ++i)
    out.emplace_back(c + ((i == 0 || i == 3) ? corner : -corner), c + (i < 2 ? corner : -corner));
  return out;
}

Vector3d steppedWorkpieceOrigin(const SteppedWorkpiece& w, const Machine& m) {
  Vector2d xy(0.5 * (m.x.min_mm + m.x.max_mm), 0.5 * (m.y.min_mm + m.y.max_mm));
  if (m.c.present) xy = m.c_axis_centre_mm;
  const double c = w.centreXY();
  return Vector3d(xy.x() - c, xy.y() - c,
                  m.table_surface_z_mm + w.fixture_height_mm + w.blank_height_mm - w.blankTopZ());
}

namespace {

// Sizes that grow from the top step down and leave a wall on every side of the next step
// (a step no larger than the one above it would have no floor to probe).
void checkSizes(YamlMap& m, const std::string& key, const std::vector<double>& sizes, double blank_x, double blank_y,
                double tool_diameter) {
  for (std::size_t k = 0; k < sizes.size(); ++k) {
    if (!(sizes[k] > 0)) m.fail(key, "step " + std::to_string(k + 1) + ": the size must be positive");
    if (k > 0 && !(sizes[k] > sizes[k - 1]))
      m.fail(key, "step " + std::to_string(k + 1) + " (" + formatNumber(sizes[k]) + " mm) must be larger than step " +
                      std::to_string(k) + " (" + formatNumber(sizes[k - 1]) + " mm): the steps grow from the top down");
  }
  // The blank is centred on the steps; the last step needs room for the tool around it.
  const double room = std::min(blank_x, blank_y) - sizes.back();
  if (!(room >= 2 * tool_diameter))
    m.fail(key, "the largest step (" + formatNumber(sizes.back()) + " mm) leaves " + formatNumber(room / 2) +
                    " mm to the blank's edge: the finishing tool (diameter " + formatNumber(tool_diameter) +
                    " mm) needs at least its diameter on each side");
}

SwExperiment readExperiment(YamlMap e, std::size_t n_steps) {
  SwExperiment x;
  x.id = e.string("id");
  x.purpose = e.stringOr("purpose", "");
  x.transition = e.choice("transition", {"non_cutting", "fast", "continuous"});
  if (x.transition == "continuous") {
    if (e.has("transition_feed")) e.fail("transition_feed", "a continuous path has no transitions: leave it out");
  } else {
    x.transition_feed_mm_per_min = e.positiveQuantity("transition_feed", Dimension::Feed);
  }
  x.tool_runout_mm = e.quantity("tool_runout", Dimension::Length);
  if (!(x.tool_runout_mm >= 0 && x.tool_runout_mm < 0.1)) e.fail("tool_runout", "expected 0 to 0.1 mm (Table 4.1: 0.004)");
  x.alternative_sizes = e.booleanOr("alternative_sizes", false);
  auto list = e.mapList("steps");
  if (list.size() != n_steps)
    e.fail("steps", "expected " + std::to_string(n_steps) + " entries, one per step of the workpiece, got " +
                        std::to_string(list.size()));
  for (auto& s : list) {
    SwCutConditions c;
    c.feed_xy_mm_per_min = s.positiveQuantity("feed_xy", Dimension::Feed);
    c.feed_z_mm_per_min = s.positiveQuantity("feed_z", Dimension::Feed);
    c.spindle_speed_rpm = s.positiveQuantity("spindle_speed", Dimension::RotSpeed);
    s.finish();
    x.steps.push_back(c);
  }
  e.finish();
  return x;
}

}  // namespace

SteppedWorkpiece loadSteppedWorkpiece(const std::string& path) {
  YamlMap root(loadYamlFile(path), path, "");
  root.choice("kind", {"stepped_workpiece"});
  SteppedWorkpiece w;
  w.file = path;
  w.name = root.stringOr("name", "stepped workpiece");

  YamlMap b = root.map("blank");
  {
    const auto size = b.quantityList("size", Dimension::Length);
    if (size.size() != 2 || !(size[0] > 0 && size[1] > 0)) b.fail("size", "expected [x, y], both positive");
    w.blank_x_mm = size[0];
    w.blank_y_mm = size[1];
  }
  w.blank_height_mm = b.positiveQuantity("height", Dimension::Length);
  w.material = readMaterial(b.map("material"));
  YamlMap ch = b.map("clamp_holes");
  w.clamp_holes = ch.integer("count");
  if (w.clamp_holes != 0 && w.clamp_holes != 4) ch.fail("count", "expected 0 or 4 (one near each corner)");
  w.clamp_hole_diameter_mm = ch.positiveQuantity("diameter", Dimension::Length);
  w.clamp_hole_inset_mm = ch.positiveQuantity("inset", Dimension::Length);
  if (!(w.clamp_hole_inset_mm > w.clamp_hole_diameter_mm / 2))
    ch.fail("inset", "a hole " + formatNumber(w.clamp_hole_inset_mm) + " mm in from the edges would break out of the blank (radius " +
                         formatNumber(w.clamp_hole_diameter_mm / 2) + " mm)");
  ch.finish();
  b.finish();

  YamlMap fx = root.map("fixture");
  w.fixture_diameter_mm = fx.positiveQuantity("diameter", Dimension::Length);
  w.fixture_height_mm = fx.positiveQuantity("height", Dimension::Length);
  // The blank is bolted through its clamp holes into the fixture's threaded holes (L719).
  if (w.clamp_holes) {
    const double r = std::hypot(std::min(w.blank_x_mm, w.blank_y_mm) / 2 - w.clamp_hole_inset_mm,
                                std::min(w.blank_x_mm, w.blank_y_mm) / 2 - w.clamp_hole_inset_mm) +
                     w.clamp_hole_diameter_mm / 2;
    if (!(r <= w.fixture_diameter_mm / 2))
      fx.fail("diameter", formatNumber(w.fixture_diameter_mm) + " mm: the clamp holes reach " + formatNumber(r, 2) +
                              " mm from the centre, beyond the fixture, whose threaded holes they bolt into (needs at least " +
                              formatNumber(2 * r, 2) + " mm)");
  }
  fx.finish();

  w.tools = readCuttingTools(root, "tools");
  w.finishing_tool = root.integer("finishing_tool");
  const CuttingTool* tool = nullptr;
  for (const auto& t : w.tools)
    if (t.number == w.finishing_tool) tool = &t;
  if (!tool) root.fail("finishing_tool", "tool T" + std::to_string(w.finishing_tool) + " is not in the tools list");

  for (auto& s : root.mapList("steps")) {
    SwStep st;
    st.size_mm = s.positiveQuantity("size", Dimension::Length);
    st.floor_depth_mm = s.positiveQuantity("floor_depth", Dimension::Length);
    if (!w.steps.empty() && !(st.floor_depth_mm > w.steps.back().floor_depth_mm))
      s.fail("floor_depth", "must be deeper than the floor of the step above (" + formatNumber(w.steps.back().floor_depth_mm) + " mm)");
    s.finish();
    w.steps.push_back(st);
  }
  if (w.steps.size() < 2 || w.steps.size() > 8) root.fail("steps", "expected 2 to 8 steps (the thesis's piece has 4)");
  // The blank's bottom lies blank_height - finishing_margin below the part's top; the base
  // under the deepest floor keeps kMinBase (our choice) so no cut comes near the fixture.
  constexpr double kMinBase = 5.0;
  if (!(w.steps.back().floor_depth_mm < w.blank_height_mm))
    root.fail("steps", "the deepest floor (" + formatNumber(w.steps.back().floor_depth_mm) + " mm) must lie above the blank's bottom (height " +
                           formatNumber(w.blank_height_mm) + " mm)");
  std::vector<double> sizes;
  for (const auto& s : w.steps) sizes.push_back(s.size_mm);
  checkSizes(root, "steps", sizes, w.blank_x_mm, w.blank_y_mm, tool->diameter_mm);
  w.alternative_sizes_mm = root.quantityList("alternative_sizes", Dimension::Length);
  if (w.alternative_sizes_mm.size() != w.steps.size())
    root.fail("alternative_sizes", "expected one size per step (" + std::to_string(w.steps.size()) + ")");
  checkSizes(root, "alternative_sizes", w.alternative_sizes_mm, w.blank_x_mm, w.blank_y_mm, tool->diameter_mm);
  w.finishing_margin_mm = root.positiveQuantity("finishing_margin", Dimension::Length);
  if (!(w.steps.back().floor_depth_mm <= w.blank_height_mm - w.finishing_margin_mm - kMinBase + 1e-9))
    root.fail("steps", "the deepest floor (" + formatNumber(w.steps.back().floor_depth_mm) + " mm) leaves " +
                           formatNumber(w.blank_height_mm - w.finishing_margin_mm - w.steps.back().floor_depth_mm) +
                           " mm of base above the fixture (blank.height " + formatNumber(w.blank_height_mm) + " mm less the " +
                           formatNumber(w.finishing_margin_mm) + " mm margin above the top); at least " + formatNumber(kMinBase) +
                           " mm are needed");

  // The clamp holes stand in the blank's corners, outside the largest step and its tool path.
  if (w.clamp_holes) {
    const double c = w.centreXY();
    const double corner = std::min(w.blank_x_mm, w.blank_y_mm) / 2 - w.clamp_hole_inset_mm;  // from the centre, per axis
    const double clear = std::max(sizes.back(), w.alternative_sizes_mm.back()) / 2 + tool->diameter_mm + w.clamp_hole_diameter_mm / 2;
    if (!(corner > clear))
      root.fail("blank", "the clamp holes at " + formatNumber(corner) + " mm from the centre (" + formatNumber(c) + ", " + formatNumber(c) +
                             ") along X and Y cut into the largest step's tool path (clear beyond " + formatNumber(clear) + " mm)");
  }

  YamlMap pr = root.map("procedure");
  w.alignment_tolerance_mm = pr.positiveQuantity("alignment_tolerance", Dimension::Length);
  w.off_before_s = pr.quantity("machine_off_before", Dimension::Duration);
  w.off_after_s = pr.quantity("machine_off_before_probing", Dimension::Duration);
  if (w.off_before_s < 0) pr.fail("machine_off_before", "must not be negative");
  if (w.off_after_s < 0) pr.fail("machine_off_before_probing", "must not be negative");
  YamlMap wu = pr.map("warm_up");
  w.warm_up_idle_s = wu.positiveQuantity("spindle_idle", Dimension::Duration);
  w.warm_up_axis_manoeuvre = wu.boolean("axis_manoeuvre");
  wu.finish();
  pr.finish();

  for (auto& e : root.mapList("experiments")) {
    const int line = e.line();
    SwExperiment x = readExperiment(e, w.steps.size());
    if (w.experiment(x.id)) throw InputError(path, line, "experiments: " + x.id + " is listed twice");
    w.experiments.push_back(std::move(x));
  }
  YamlMap pb = root.map("probing");
  w.probing.wall_positions = pb.numberList("wall_positions");
  for (double f : w.probing.wall_positions)
    if (!(f > -1 && f < 1))
      pb.fail("wall_positions", formatNumber(f) + ": expected fractions of the wall's half length, strictly between -1 and 1");
  w.probing.wall_levels = pb.numberList("wall_levels");
  for (double f : w.probing.wall_levels)
    if (!(f > 0 && f < 1))
      pb.fail("wall_levels", formatNumber(f) + ": expected fractions of the wall's height below its top edge, strictly between 0 and 1");
  if (w.probing.wall_positions.size() * w.probing.wall_levels.size() < 3)
    pb.fail("wall_positions", "a wall's plane needs at least 3 points (positions x levels)");
  w.probing.top_grid = pb.number("top_grid");
  if (!(w.probing.top_grid > 0 && w.probing.top_grid < 1)) pb.fail("top_grid", "expected a fraction of the top's half size, between 0 and 1");
  w.probing.tip_diameter_mm = pb.positiveQuantity("tip_diameter", Dimension::Length);
  w.probing.feed_mm_per_min = pb.positiveQuantity("feed", Dimension::Feed);
  w.probing.positioning_feed_mm_per_min = pb.positiveQuantity("positioning_feed", Dimension::Feed);
  w.probing.approach_mm = pb.positiveQuantity("approach", Dimension::Length);
  w.probing.overtravel_mm = pb.positiveQuantity("overtravel", Dimension::Length);
  w.probing.clearance_mm = pb.positiveQuantity("clearance", Dimension::Length);
  w.probing.repeatability_mm = pb.positiveQuantity("repeatability", Dimension::Length);
  w.probing.step3_wall_passes = pb.has("step3_wall_passes") ? pb.integer("step3_wall_passes") : 1;
  if (!(w.probing.step3_wall_passes >= 1 && w.probing.step3_wall_passes <= 10))
    pb.fail("step3_wall_passes", "expected 1 (no repeat) to 10");
  if (w.probing.step3_wall_passes > 1 && w.steps.size() < 3) pb.fail("step3_wall_passes", "the piece has no step 3");
  pb.finish();

  YamlMap mc = root.map("machining");
  {
    YamlMap r = mc.map("roughing");
    auto& g = w.machining;
    g.roughing_spindle_rpm = r.positiveQuantity("spindle_speed", Dimension::RotSpeed);
    g.roughing_feed_xy_mm_per_min = r.positiveQuantity("feed_xy", Dimension::Feed);
    g.roughing_depth_per_level_mm = r.positiveQuantity("depth_per_level", Dimension::Length);
    if (!(g.roughing_depth_per_level_mm <= tool->flute_length_mm))
      r.fail("depth_per_level", formatNumber(g.roughing_depth_per_level_mm) + " mm is deeper than the flutes of T" +
                                    std::to_string(tool->number) + " (" + formatNumber(tool->flute_length_mm) + " mm)");
    r.finish();
    g.stepover = mc.number("stepover");
    if (!(g.stepover > 0.05 && g.stepover <= 0.9)) mc.fail("stepover", "expected a fraction of the tool's diameter, 0.05 to 0.9");
    g.lead_mm = mc.positiveQuantity("lead", Dimension::Length);
    g.clearance_mm = mc.positiveQuantity("clearance", Dimension::Length);
  }
  mc.finish();
  // One finishing pass cuts a wall over its whole height (and the margin above it).
  for (std::size_t k = 0; k < w.steps.size(); ++k) {
    const double h = w.steps[k].floor_depth_mm - (k ? w.steps[k - 1].floor_depth_mm : 0.0) + w.finishing_margin_mm;
    if (!(h <= tool->flute_length_mm))
      root.fail("steps", "step " + std::to_string(k + 1) + ": its wall (" + formatNumber(h) + " mm with the margin) is taller than the flutes of the finishing tool T" +
                             std::to_string(tool->number) + " (" + formatNumber(tool->flute_length_mm) + " mm), which finish a wall in one pass");
  }
  w.cmm = readCmm(root.map("cmm"));
  root.finish();
  // Every layout must fit every size set the experiments cut (the shipped and the W2/W5 one).
  try {
    probePoints(w, nominalFeatures(w));
    probePoints(w, nominalFeatures(w, w.alternative_sizes_mm));
  } catch (const InputError& e) {
    throw InputError(path, 0, std::string("probing: ") + e.what());
  }
  return w;
}

std::vector<SwProbePoint> probePoints(const SteppedWorkpiece& w, const std::vector<NominalFeature>& features) {
  const double keep = w.probing.tip_diameter_mm / 2 + 0.5;  // from a face's edges
  std::vector<SwProbePoint> out;
  auto add = [&](const NominalFeature& f, int& n, const Vector3d& p) {
    // Inside the face: within its extent less `keep` along u and v (a floor's ring: across it).
    // Inside the face by `keep`: a floor's points lie on its ring's mid-line, half the ring's
    // width from the step and from the next; the others within their extent along u and v.
    const Vector3d d = p - f.point_mm;
    bool ok = f.role == "floor" ? f.radius_mm >= keep
                                : std::abs(d.dot(f.u)) <= f.half_u_mm - keep + 1e-9 && std::abs(d.dot(f.v())) <= f.half_v_mm - keep + 1e-9;
    for (const auto& c : clampHoleCentres(w))
      if ((p.head<2>() - c).norm() < w.clamp_hole_diameter_mm / 2 + keep)
        throw InputError(w.file, 0, "feature " + f.id + ": point " + std::to_string(n + 1) + " lies " +
                                        formatNumber((p.head<2>() - c).norm(), 3) + " mm from the centre of a clamp hole (x " +
                                        formatNumber(c.x()) + ", y " + formatNumber(c.y()) + "), within its radius + " +
                                        formatNumber(keep) + " mm; move the holes (blank.clamp_holes.inset) or the points");
    if (!ok)
      throw InputError(w.file, 0, "feature " + f.id + ": point " + std::to_string(n + 1) + " lies within " + formatNumber(keep) +
                                      " mm (the ball's radius + 0.5 mm) of the face's edge; move it inward or use a smaller ball");
    out.push_back({f.id, ++n, p, f.direction});
  };
  for (const auto& f : features) {
    int n = 0;
    if (f.role == "datum_top") {
      const double g = w.probing.top_grid;
      for (double b : {-g, 0.0, g})
        for (double a : {-g, 0.0, g}) add(f, n, f.point_mm + a * f.half_u_mm * f.u + b * f.half_v_mm * f.v());
    } else if (f.role == "wall") {
      const double top = f.point_mm.z() + f.half_v_mm, height = 2 * f.half_v_mm;
      for (double level : w.probing.wall_levels)
        for (double a : w.probing.wall_positions) {
          Vector3d p = f.point_mm + a * f.half_u_mm * f.u;
          p.z() = top - level * height;
          add(f, n, p);
        }
    } else if (f.role == "floor") {
      // The ring's mid-line square (half size h about the centre): per side (+X, +Y, -X, -Y)
      // the points at -h/2 and +h/2 along it, then the middle of the +X side.
      const double h = f.half_u_mm;
      const Vector3d c = f.point_mm;
      const Vector3d x = Vector3d::UnitX(), y = Vector3d::UnitY();
      for (const auto& [side, along] : {std::pair{x, y}, std::pair{y, Vector3d(-x)}, std::pair{Vector3d(-x), Vector3d(-y)}, std::pair{Vector3d(-y), x}})
        for (double s : {-0.5, 0.5}) add(f, n, c + h * side + s * h * along);
      add(f, n, c + h * x);
    }
  }
  return out;
}

std::vector<NominalFeature> nominalFeatures(const SteppedWorkpiece& w, const std::vector<double>& sizes_mm) {
  std::vector<double> sizes = sizes_mm;
  if (sizes.empty())
    for (const auto& s : w.steps) sizes.push_back(s.size_mm);
  if (sizes.size() != w.steps.size())
    throw InputError(w.file, 0, "nominalFeatures: " + std::to_string(sizes.size()) + " sizes for " + std::to_string(w.steps.size()) + " steps");
  // The steps are centred on the top step's centre, whatever set of sizes is cut (the origin
  // stays at the shipped top step's corner, notes §1.2).
  const double c = w.centreXY();
  std::vector<NominalFeature> out;
  NominalFeature top;
  top.id = "TOP";
  top.kind = "plane";
  top.role = "datum_top";
  top.group = "datum";
  top.point_mm = Vector3d(c, c, 0);
  top.direction = Vector3d::UnitZ();
  top.u = Vector3d::UnitX();
  top.half_u_mm = top.half_v_mm = sizes.front() / 2;
  out.push_back(top);
  for (std::size_t k = 0; k < sizes.size(); ++k) {
    const double half = sizes[k] / 2;
    const double z_top = k == 0 ? 0.0 : -w.steps[k - 1].floor_depth_mm;
    const double z_floor = -w.steps[k].floor_depth_mm;
    const std::string group = "S" + std::to_string(k + 1);
    struct Side {
      const char* name;
      Vector3d n, u;
    };
    for (const Side& s : {Side{"XP", Vector3d::UnitX(), Vector3d::UnitY()}, Side{"XN", -Vector3d::UnitX(), -Vector3d::UnitY()},
                          Side{"YP", Vector3d::UnitY(), -Vector3d::UnitX()}, Side{"YN", -Vector3d::UnitY(), Vector3d::UnitX()}}) {
      NominalFeature f;
      f.id = group + "_" + s.name;
      f.kind = "plane";
      f.role = "wall";
      f.group = group;
      f.index = static_cast<int>(k + 1);
      f.direction = s.n;
      f.u = s.u;  // along the wall; v = n x u is then +Z for every side
      f.point_mm = Vector3d(c, c, (z_top + z_floor) / 2) + half * s.n;
      f.half_u_mm = half;
      f.half_v_mm = (z_top - z_floor) / 2;
      f.angle_deg = radToDeg(std::atan2(s.n.y(), s.n.x()));
      out.push_back(f);
    }
    // The floor: a square ring from this step out to the next (the blank's edge for the last).
    const double outer = k + 1 < sizes.size() ? sizes[k + 1] / 2 : std::min(w.blank_x_mm, w.blank_y_mm) / 2;
    NominalFeature fl;
    fl.id = group + "_F";
    fl.kind = "plane";
    fl.role = "floor";
    fl.group = group;
    fl.index = static_cast<int>(k + 1);
    fl.point_mm = Vector3d(c, c, z_floor);
    fl.direction = Vector3d::UnitZ();
    fl.u = Vector3d::UnitX();
    fl.half_u_mm = fl.half_v_mm = (half + outer) / 2;  // the ring's mid-line square
    fl.radius_mm = (outer - half) / 2;                 // half the ring's width (probe points keep inside it)
    out.push_back(fl);
  }
  return out;
}

Workpiece steppedWorkpieceStock(const SteppedWorkpiece& w) {
  Workpiece s;
  s.file = w.file;
  s.name = w.name;
  const double c = w.centreXY();
  // The blank before roughing, faced on both sides (L695-700): its top stands the finishing
  // margin above the finished top, which finishing faces at z 0 with step 1 (L739).
  const double top = w.blankTopZ(), bottom = top - w.blank_height_mm;
  s.stock_min_mm = Vector3d(c - w.blank_x_mm / 2, c - w.blank_y_mm / 2, bottom);
  s.stock_max_mm = Vector3d(c + w.blank_x_mm / 2, c + w.blank_y_mm / 2, top);
  int i = 0;
  for (const auto& h : clampHoleCentres(w))
    s.holes.push_back({h, w.clamp_hole_diameter_mm / 2, bottom - 1, top + 1, "clamp hole " + std::to_string(++i)});
  s.obstacles.push_back({Vector2d(c, c), w.fixture_diameter_mm / 2, bottom - w.fixture_height_mm, bottom, "fixture"});
  s.material = w.material;
  s.tools = w.tools;
  s.cmm = w.cmm;
  s.probe_tip_diameter_mm = w.probing.tip_diameter_mm;
  return s;
}

}  // namespace probeloop::parts
