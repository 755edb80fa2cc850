#include "planner/stepped_workpiece.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "planner/piece_manifest.hpp"

namespace probeloop::planner {

using Eigen::Vector2d;
using Eigen::Vector3d;
using parts::SteppedWorkpiece;

namespace {

std::string xyz(const Vector3d& v) {
  return "(" + formatNumber(v.x(), 4) + ", " + formatNumber(v.y(), 4) + ", " + formatNumber(v.z(), 4) + ")";
}

// The material as the programs leave it, box by box (part frame): step j's box is its square
// from its own floor up to its top (the floor of step j - 1, or the top face), the base is the
// blank below the deepest floor. Roughed, a box is the margin larger and its top the margin
// higher; finishing finishes the tops (the top face, then each floor) and the walls step by
// step. The clamp holes are left out (less material: the check errs on the safe side).
struct Material {
  const SteppedWorkpiece& w;
  std::vector<double> half;  // the cut sizes / 2
  // Compensation (mm): a finished step's walls as far out as its outermost compensated wall
  // (the safe side), its floor where the compensated path cut it.
  std::vector<double> wall_out, floor_up;
  bool blank = true;         // before roughing: the whole blank
  int tops_finished = 0;     // box tops finished: 1 = the top face, 1 + k = the floor of step k too
  int walls_finished = 0;    // steps whose four walls are finished

  struct Box {
    double hx, hy, z_lo, z_hi;
  };
  std::vector<Box> boxes() const {
    const double m = w.finishing_margin_mm, c_bottom = w.blankTopZ() - w.blank_height_mm;
    const double bx = w.blank_x_mm / 2, by = w.blank_y_mm / 2;
    if (blank)
      return {{bx, by, c_bottom, w.blankTopZ()},
              {w.fixture_diameter_mm / 2, w.fixture_diameter_mm / 2, c_bottom - w.fixture_height_mm, c_bottom}};
    std::vector<Box> out;
    const std::size_t n = half.size();
    const auto shift = [](const std::vector<double>& v, std::size_t j) { return j < v.size() ? v[j] : 0.0; };
    // Box j's top: the floor of step j - 1 (0: the top face), where its compensated pass cut it
    // once finished, the margin above the nominal floor before; its bottom: its own floor,
    // reaching down to a floor the compensation lowered.
    for (std::size_t j = 0; j < n; ++j) {
      const bool top_done = static_cast<int>(j) < tops_finished;
      const double top = j == 0 ? 0.0 : -w.steps[j - 1].floor_depth_mm + (top_done ? shift(floor_up, j - 1) : 0.0);
      const double h = half[j] + (static_cast<int>(j) < walls_finished ? shift(wall_out, j) : m);
      const double z_hi = top + (top_done ? 0.0 : m);
      out.push_back({h, h, -w.steps[j].floor_depth_mm + std::min(shift(floor_up, j), 0.0), z_hi});
    }
    const bool base_done = static_cast<int>(n) < tops_finished;
    const double base_top = -w.steps.back().floor_depth_mm + (base_done ? shift(floor_up, n - 1) : m);
    out.push_back({bx, by, c_bottom, base_top});
    // The fixture under the blank (a box round its circle: the safe side).
    out.push_back({w.fixture_diameter_mm / 2, w.fixture_diameter_mm / 2, c_bottom - w.fixture_height_mm, c_bottom});
    return out;
  }
};

// Distance in XY from p to the rectangle |x| <= hx, |y| <= hy (0 inside).
double rectDistance(const Vector2d& p, double hx, double hy) {
  const double dx = std::max(std::fabs(p.x()) - hx, 0.0), dy = std::max(std::fabs(p.y()) - hy, 0.0);
  return std::hypot(dx, dy);
}

class Builder {
 public:
  Builder(const SteppedWorkpiece& w, const std::string& experiment, const parts::Machine& m, parts::Dialect d,
          const parts::SwCompensation* comp)
      : w_(w), m_(m), dialect_(d), files_(swFiles(d)), material_{w, {}, {}, {}} {
    comp_ = comp;
    e_ = w.experiment(experiment);
    if (comp_)
      for (const auto& s : comp_->steps) {
        material_.wall_out.push_back(-toProgram(std::min({s.wall_um[0], s.wall_um[1], s.wall_um[2], s.wall_um[3]})));
        material_.floor_up.push_back(toProgram(s.floor_um));
      }
    if (!e_) {
      std::string ids;
      for (const auto& x : w.experiments) ids += (ids.empty() ? "" : ", ") + x.id;
      throw InputError(w.file, 0, "experiments: no experiment '" + experiment + "' (the description has " + ids + ")");
    }
    if (comp_ && comp_->experiment != e_->id)
      throw InputError(comp_->file, 0, "experiment: '" + comp_->experiment + "', but " + e_->id +
                                           " is planned (its errors belong to its own feeds and times)");
    if (comp_ && comp_->steps.size() != e_->steps.size())
      throw InputError(comp_->file, 0, "steps: " + std::to_string(comp_->steps.size()) + " given, experiment " + e_->id + " has " +
                                           std::to_string(e_->steps.size()));
    // Roughing leaves the finishing margin: a wall moved out or a floor raised by more would be
    // cut in the air and stay where roughing left it.
    if (comp_)
      for (std::size_t k = 0; k < comp_->steps.size(); ++k) {
        const auto& c = comp_->steps[k];
        const double mrg_um = w.finishing_margin_mm * 1e3;
        for (int i = 0; i < 4; ++i)
          if (c.wall_um[static_cast<std::size_t>(i)] < -mrg_um)
            throw InputError(comp_->file, 0, "steps[" + std::to_string(k) + "].wall_um." + parts::kSwWalls[i] + ": " +
                                                 formatNumber(c.wall_um[static_cast<std::size_t>(i)]) + " um moves the wall out by more "
                                                 "than the finishing margin (" + formatNumber(mrg_um) + " um) roughing leaves");
        if (c.floor_um > mrg_um)
          throw InputError(comp_->file, 0, "steps[" + std::to_string(k) + "].floor_um: " + formatNumber(c.floor_um) +
                                               " um raises the floor by more than the finishing margin (" + formatNumber(mrg_um) + " um)");
      }
    sizes_ = w.sizesFor(*e_);
    for (double s : sizes_) material_.half.push_back(s / 2);
    features_ = parts::nominalFeatures(w, sizes_);
    O_ = parts::steppedWorkpieceOrigin(w, m);
    tool_ = &w.finishingTool();
    r_ = tool_->diameter_mm / 2;
    rt_ = w.probing.tip_diameter_mm / 2;
    c_ = w.centreXY();
    // Square contours cover their corners only with a step of at most r sqrt 2.
    step_ = std::min(w.machining.stepover * tool_->diameter_mm, r_ * std::sqrt(2.0) - 0.01);
    z_clear_ = w.blankTopZ() + w.machining.clearance_mm;
    checkInputs();
  }

  SteppedWorkpiecePlan build() {
    for (std::size_t i = 0; i < features_.size(); ++i) {
      parts::ManifestFeature f;
      f.nominal = features_[i];
      f.position = static_cast<int>(i + 1);  // the probing program visits them in this order
      man_.features.push_back(f);
    }
    roughing();
    finishing();
    probing();
    walk();
    manifest();
    plan_.experiment = e_->id;
    plan_.sizes_mm = sizes_;
    plan_.programs = std::move(programs_);
    plan_.manifest = std::move(man_);
    plan_.cmm_points_csv = cmmCsv();
    return std::move(plan_);
  }

 private:
  // --- inputs the programs cannot be made of -------------------------------------------
  void checkInputs() const {
    const double f_xy = std::min(m_.x.max_feed_mm_per_min, m_.y.max_feed_mm_per_min), f_z = m_.z.max_feed_mm_per_min;
    const std::string key = "experiments[" + e_->id + "]";
    auto feed = [&](double v, double max, const std::string& k, const char* axes) {
      if (!(v <= max))
        throw InputError(w_.file, 0, k + ": " + formatNumber(v) + " mm/min exceeds the machine's " + axes + " max_feed of " +
                                         formatNumber(max) + " mm/min (" + m_.file + ")");
    };
    for (std::size_t k = 0; k < e_->steps.size(); ++k) {
      const auto& s = e_->steps[k];
      const std::string sk = key + ".steps[" + std::to_string(k + 1) + "]";
      feed(s.feed_xy_mm_per_min, f_xy, sk + ".feed_xy", "X/Y");
      feed(s.feed_z_mm_per_min, f_z, sk + ".feed_z", "Z");
    }
    if (e_->transition != "continuous") feed(e_->transition_feed_mm_per_min, f_xy, key + ".transition_feed", "X/Y");
    feed(w_.machining.roughing_feed_xy_mm_per_min, f_xy, "machining.roughing.feed_xy", "X/Y");
    feed(w_.probing.feed_mm_per_min, std::min(f_xy, f_z), "probing.feed", "X/Y/Z");
    feed(w_.probing.positioning_feed_mm_per_min, std::min(f_xy, f_z), "probing.positioning_feed", "X/Y/Z");
    // Z reach: the gauge line at the deepest cut and at the clearance plane within the travel.
    const double deepest = O_.z() - w_.steps.back().floor_depth_mm, clear = O_.z() + z_clear_;
    auto reach = [&](double length, double lowest_tip, const std::string& k, const std::string& what) {
      if (clear + length > m_.z.max_mm + 1e-9)
        throw InputError(w_.file, 0, k + ": " + formatNumber(length) + " mm: " + what + " at the clearance plane (tip Z " +
                                         formatNumber(round4(clear)) + ") puts the gauge line at Z " + formatNumber(round4(clear + length)) +
                                         ", above the Z travel (max " + formatNumber(m_.z.max_mm) + " mm, " + m_.file + ")");
      if (lowest_tip + length < m_.z.min_mm - 1e-9)
        throw InputError(w_.file, 0, k + ": " + formatNumber(length) + " mm: " + what + " cannot reach down to tip Z " +
                                         formatNumber(round4(lowest_tip)) + " within the Z travel (gauge line min " +
                                         formatNumber(m_.z.min_mm) + " mm, " + m_.file + "): it needs at least " +
                                         formatNumber(round4(m_.z.min_mm - lowest_tip)) + " mm");
    };
    reach(tool_->length_mm, deepest, "tools[T" + std::to_string(tool_->number) + "].length", "the finishing tool");
    // A tool is changed at the tool-change height: the new tool (or the probe) must hang
    // above the clearance plane there, or it is loaded (and the spindle started) in the part.
    auto hangs = [&](double length, double tip_z, const std::string& what) {
      if (m_.tool_change.z_mm - length < tip_z - 1e-9)
        throw InputError(m_.file, 0, "tool_change.z: " + formatNumber(m_.tool_change.z_mm) + " mm puts the tip of " + what + " (" +
                                         formatNumber(length) + " mm) at Z " + formatNumber(round4(m_.tool_change.z_mm - length)) +
                                         ", below the clearance plane of " + w_.file + " (tip Z " + formatNumber(round4(tip_z)) + ")");
    };
    hangs(tool_->length_mm, clear, "tool T" + std::to_string(tool_->number));
    hangs(m_.probe.length_mm, O_.z() + rt_ + w_.machining.clearance_mm, "the probe");
    if (!(step_ > 0.1))
      throw InputError(w_.file, 0, "tools[T" + std::to_string(tool_->number) + "].diameter: " + formatNumber(tool_->diameter_mm) +
                                       " mm is too small for the contours (step " + formatNumber(step_) + " mm)");
    reach(m_.probe.length_mm, deepest + rt_, "probe.length (" + m_.file + ")", "the probe");
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
    P().add(std::move(op), std::move(n));
    states_.back().push_back(material_);
  }
  // Machine coordinates (rounded as written) of a point given relative to the steps' centre.
  double mx(double qx) const { return round4(O_.x() + c_ + qx); }
  double my(double qy) const { return round4(O_.y() + c_ + qy); }
  double mz(double z) const { return round4(O_.z() + z); }
  Vector3d mach(const Vector2d& q, double z) const { return {mx(q.x()), my(q.y()), mz(z)}; }

  void rapidXY(const Vector2d& q, const std::string& w) {
    add(gcode::Rapid{mx(q.x()), my(q.y()), std::nullopt}, w);
    pos_ = q;
  }
  void rapidZ(double z, const std::string& w) { add(gcode::Rapid{std::nullopt, std::nullopt, mz(z)}, w); }
  void feedXY(const Vector2d& q, double F, const std::string& w, bool cut = false, int ci = -1) {
    std::optional<double> x, y;
    if (std::fabs(q.x() - pos_.x()) > 1e-12) x = mx(q.x());
    if (std::fabs(q.y() - pos_.y()) > 1e-12) y = my(q.y());
    if (!x && !y) return;
    add(gcode::Feed{x, y, std::nullopt, round3(F)}, w, cut, ci);
    pos_ = q;
  }
  void feedZ(double z, double F, const std::string& w, bool cut = false) {
    add(gcode::Feed{std::nullopt, std::nullopt, mz(z), round3(F)}, w, cut);
  }
  int addCut(const std::string& id, const std::string& feature, int step, const Vector2d& from, const Vector2d& to, double z) {
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

  void newProgram(const std::string& role, const std::string& file, int number, const std::string& title) {
    programs_.push_back(newNotedProgram(m_, role, file, number, title));
    states_.emplace_back();
    P().program.header = {
        "machine: " + m_.name,
        "part: " + w_.name + ", experiment " + e_->id + "; part frame origin at " + xyz(O_) +
            " [machine], the steps centred on X " + formatNumber(O_.x() + c_, 4) + " Y " + formatNumber(O_.y() + c_, 4),
        "coordinates: G" + std::to_string(53 + m_.work_offset) + " zeroed = machine coordinates of the tool tip with G43",
    };
    add(gcode::RapidMachineZ{m_.tool_change.z_mm}, "start: retract to the tool-change height");
    if (m_.b.present) add(gcode::RotateB{0}, "start: table level (B 0)");
    if (m_.c.present) add(gcode::RotateC{0}, "start: C 0");
  }
  void toolChange(int tool, const std::string& w) {
    add(gcode::RapidMachineZ{m_.tool_change.z_mm}, w + ": retract to the tool-change height");
    add(gcode::ToolChange{tool, tool != m_.tool_change.empty_tool}, w);
  }
  void end(bool spindle) {
    add(gcode::RapidMachineZ{m_.tool_change.z_mm}, "end: retract to the tool-change height");
    if (spindle) add(gcode::Spindle{0}, "end: spindle off");
    add(gcode::ToolChange{m_.tool_change.empty_tool, false}, "end: empty the spindle");
  }
  std::string toolLine() const {
    return "T" + std::to_string(tool_->number) + ": " + (tool_->name.empty() ? tool_->kind : tool_->name) + ", d = " +
           formatNumber(tool_->diameter_mm) + " mm, length " + formatNumber(tool_->length_mm) + " mm";
  }

  // One closed square contour of half size s about the centre, clockwise from its (-s, s)
  // corner (where the tool stands).
  void contour(double s, double F, const std::string& w, int ci, bool cut = true) {
    const Vector2d corners[4] = {{s, s}, {s, -s}, {-s, -s}, {-s, s}};
    for (const auto& q : corners) feedXY(q, F, w, cut, ci);
  }

  // --- roughing (our choice: the thesis's preparation, L695-700) ----------------------------
  void roughing() {
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

  // --- finishing: the experiment (Table 4.1, Sec. 4.1) ------------------------------------
  // The path of step k at its depth (floor contours, then the walls as the transition says);
  // `air` replays it at the clearance plane without cutting (the warm-up's axis manoeuvre).
  void stepPath(std::size_t k, bool air, const std::string& w) {
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

  void finishing() {
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

  // --- on-machine probing (Sec. 3.4, L1040) ------------------------------------------------
  struct Planned {
    Vector3d start, end, contact;
    int index;
  };
  Planned planPoint(const parts::SwProbePoint& p, int position, int point, bool cmm) {
    const Vector3d n = p.normal;
    const Vector3d contact = O_ + p.contact_mm + rt_ * n;
    parts::ManifestPoint mp;
    mp.feature = p.feature;
    mp.position = position;
    mp.point = point;
    mp.contact_mm = contact;
    mp.approach = -n;
    man_.points.push_back(mp);
    if (cmm) cmm_.push_back({p.feature, point, p.contact_mm, n});
    const Vector3d s = contact + w_.probing.approach_mm * n, e = contact - w_.probing.overtravel_mm * n;
    return {Vector3d(round4(s.x()), round4(s.y()), round4(s.z())), Vector3d(round4(e.x()), round4(e.y()), round4(e.z())), contact,
            static_cast<int>(man_.points.size()) - 1};
  }

  void probing() {
    newProgram("probing", files_.probing, 3003,
               "probeloop stepped workpiece: on-machine probing [seed 000 Sec. 3.4, L1040] - generated, do not edit");
    P().program.log_file = files_.log;
    P().program.header.push_back("probe T" + std::to_string(m_.probe.tool) + " with the piece's stylus, ball d = " +
                                 formatNumber(w_.probing.tip_diameter_mm) + " mm; log: PT 1 <position> <point> x y z");
    toolChange(m_.probe.tool, "probing: probe in");
    const double z_cp = mz(rt_ + w_.machining.clearance_mm);  // the ball's bottom `clearance` above the top
    const double Fp = round3(w_.probing.positioning_feed_mm_per_min), Fm = round3(w_.probing.feed_mm_per_min);
    const auto pts = parts::probePoints(w_, features_);
    auto positionOf = [&](const std::string& id) { return man_.feature(id)->position; };
    auto probeFeature = [&](const std::string& id, const std::vector<const parts::SwProbePoint*>& list, int first_point, bool cmm,
                            const std::string& w) {
      add(gcode::Rapid{std::nullopt, std::nullopt, z_cp}, w + ": clearance plane");
      bool first = true;
      int k = first_point;
      Vector3d prev = Vector3d::Zero();
      for (const auto* p : list) {
        const Planned q = planPoint(*p, positionOf(id), k, cmm);
        const std::string wp = w + " point " + std::to_string(k);
        // From one start to the next straight when the stylus passes clear of the part (a
        // floor's points go round a corner of the step: over it, by the clearance plane).
        if (!first && !pathClear(prev, q.start, rt_)) {
          add(gcode::Rapid{std::nullopt, std::nullopt, z_cp}, wp + ": up to the clearance plane");
          first = true;
        }
        if (first) add(gcode::Rapid{q.start.x(), q.start.y(), std::nullopt}, wp + ": above the start");
        first = false;
        prev = q.start;
        add(gcode::ProtectedMove{q.start.x(), q.start.y(), q.start.z(), Fp}, wp + ": protected move to the start");
        OpNote n;
        n.where = wp;
        n.point_index = q.index;
        n.contact_mm = q.contact;
        add(gcode::ProbeMove{q.end.x(), q.end.y(), q.end.z(), Fm, positionOf(id), k}, n);
        OpNote back;
        back.where = wp + ": back along the approach line";
        back.retract = true;
        add(gcode::Rapid{q.start.x(), q.start.y(), q.start.z()}, back);
        ++k;
      }
      add(gcode::Rapid{std::nullopt, std::nullopt, z_cp}, w + ": up to the clearance plane");
    };
    for (const auto& f : features_) {
      std::vector<const parts::SwProbePoint*> list;
      for (const auto& p : pts)
        if (p.feature == f.id) list.push_back(&p);
      probeFeature(f.id, list, 1, true, "probing " + f.id);
    }
    // The repeatability check (L769): step 3's wall points again, numbered on.
    for (int pass = 2; pass <= w_.probing.step3_wall_passes; ++pass)
      for (const auto& f : features_) {
        if (f.role != "wall" || f.index != 3) continue;
        std::vector<const parts::SwProbePoint*> list;
        for (const auto& p : pts)
          if (p.feature == f.id) list.push_back(&p);
        probeFeature(f.id, list, static_cast<int>(list.size()) * (pass - 1) + 1, false,
                     "probing " + f.id + " repeat " + std::to_string(pass - 1));
      }
    add(gcode::RapidMachineZ{m_.tool_change.z_mm}, "end: retract to the tool-change height");
    add(gcode::ToolChange{m_.tool_change.empty_tool, false}, "end: probe out");
  }

  // Whether a ball of radius rho moving from a to b (machine coordinates of its centre) keeps
  // clear of the material as it is now.
  bool pathClear(const Vector3d& a, const Vector3d& b, double rho) const {
    const Vector3d off = O_ + Vector3d(c_, c_, 0);
    const auto boxes = material_.boxes();
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.25)));
    for (int i = 0; i <= n; ++i) {
      const Vector3d q = a - off + (b - a) * (static_cast<double>(i) / n);
      for (const auto& x : boxes)
        if (q.z() - rho < x.z_hi - 1e-6 && rectDistance(q.head<2>(), x.hx, x.hy) < rho + 0.5) return false;
    }
    return true;
  }

  // --- walking: clock and checks ----------------------------------------------------------
  void check(const Motion& mo, const Material& mat) const {
    const std::string tool = mo.tool.probe ? "probe" : "tool T" + std::to_string(mo.tool.number);
    auto fail = [&](const std::string& msg) { throw SafetyError(*mo.program + ": " + mo.note->where + ": " + msg); };
    const Vector3d off = O_ + Vector3d(c_, c_, 0);
    const Vector3d qa = mo.from_tip - off, qb = mo.to_tip - off;  // relative to the steps' centre, part z
    const double rho = mo.tool.radius_mm, below = mo.tool.probe ? rho : 0.0;
    const double top = mat.blank ? w_.blankTopZ() : mat.boxes().front().z_hi;
    if (mo.kind == MotionKind::Rapid && std::min(qa.z(), qb.z()) - below < top - 1e-9) {
      int axes = 0;
      for (int i = 0; i < 3; ++i) axes += std::fabs(qa(i) - qb(i)) > 1e-3;
      if (axes > 1)
        fail("G0 from " + xyz(mo.from_tip) + " to " + xyz(mo.to_tip) + " moves " + std::to_string(axes) + " axes with the " + tool +
             " below the top of the part (a G0 may dog-leg: only G1 there)");
    }
    if (mo.note->cut || mo.note->retract || mo.kind == MotionKind::Measuring) return;
    if (mo.kind == MotionKind::MachineZ && qb.z() >= qa.z()) return;  // straight up to the tool-change height
    // Straight up: in every state the material only narrows upward (roughing clears each level
    // at least as wide as the one below it; the steps shrink upward), so nothing is met.
    if ((qa.head<2>() - qb.head<2>()).norm() < 1e-9 && qb.z() >= qa.z()) return;
    const auto boxes = mat.boxes();
    // Samples 0.02 mm apart: a graze between two of them stays under 0.01 mm.
    const double len = (qb - qa).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / 0.02)));
    for (int i = 0; i <= n; ++i) {
      const Vector3d q = qa + (qb - qa) * (static_cast<double>(i) / n);
      for (const auto& b : boxes) {
        if (q.z() - below >= b.z_hi - 1e-6) continue;
        const double d = rectDistance(q.head<2>(), b.hx, b.hy);
        if (d < rho - 1e-6)
          fail(std::string(mo.what) + " from " + xyz(mo.from_tip) + " to " + xyz(mo.to_tip) + " would take the " + tool +
               " into material at " + xyz(q + off) + ": " + formatNumber(d, 3) + " mm from a face, its radius " +
               formatNumber(rho, 3) + " mm");
      }
    }
  }

  std::vector<WalkerTool> walkerTools() const {
    WalkerTool c;
    c.number = tool_->number;
    c.length_mm = tool_->length_mm;
    c.radius_mm = r_;
    c.cutter = true;
    WalkerTool p;
    p.number = m_.probe.tool;
    p.length_mm = m_.probe.length_mm;
    p.radius_mm = rt_;
    p.probe = true;
    return {c, p};
  }

  void walk() {
    ProgramWalker walker(m_, walkerTools());
    double offset = 0;  // the procedure's waits, machine off (not in any program)
    const double waits[3] = {0, w_.off_before_s, w_.off_after_s};
    WalkTimes total;
    for (std::size_t i = 0; i < programs_.size(); ++i) {
      auto& p = programs_[i];
      offset += waits[i];
      const auto& states = states_[i];
      const OpNote* base = p.notes.data();
      walker.setCheck([&](const Motion& mo) { check(mo, states[static_cast<std::size_t>(mo.note - base)]); });
      const double t0 = walker.time();
      std::vector<double> before(p.program.ops.size(), NAN), after(p.program.ops.size(), NAN);
      walker.run(p, [&](std::size_t op, double a, double b) {
        before[op] = a + offset;
        after[op] = b + offset;
        const auto& n = p.notes[op];
        if (n.cut_index >= 0) {  // a cut of several moves: from its first to its last
          auto& c = man_.cuts[static_cast<std::size_t>(n.cut_index)];
          if (std::isnan(c.start_s)) c.start_s = a + offset;
          c.end_s = b + offset;
        }
        if (n.point_index >= 0) man_.points[static_cast<std::size_t>(n.point_index)].time_in_cycle_s = b - t0;
      });
      plan_.start_s.push_back(t0 + offset);
      plan_.duration_s.push_back(walker.time() - t0);
      plan_.times.push_back(walker.times() - total);
      total = walker.times();
      if (p.role == "finishing") {
        for (std::size_t k = 0; k < sizes_.size(); ++k) {
          SwPlannedStep s;
          s.step = static_cast<int>(k + 1);
          s.conditions = e_->steps[k];
          s.start_s = INFINITY;
          s.end_s = -INFINITY;
          for (std::size_t op = step_first_op_[k]; op <= step_last_op_[k]; ++op)
            if (p.notes[op].cut) {
              s.start_s = std::min(s.start_s, before[op]);
              s.end_s = std::max(s.end_s, after[op]);
            }
          double a = INFINITY, b = -INFINITY;
          for (const auto& c : man_.cuts)
            if (c.cycle == s.step && c.program == "finishing" && c.feature.size() > 3 && c.feature.substr(c.feature.size() - 2) != "_F" &&
                c.feature != "TOP") {
              a = std::min(a, c.start_s);
              b = std::max(b, c.end_s);
            }
          s.walls_mid_s = (a + b) / 2;
          plan_.steps.push_back(s);
        }
        for (auto& s : plan_.steps) s.temp_state_min = (s.walls_mid_s - plan_.steps.front().start_s) / 60;
      }
    }
  }

  // --- manifest and CMM plan --------------------------------------------------------------
  void manifest() {
    auto& m = man_;
    m.kind = "stepped_workpiece";
    m.dialect = parts::dialectName(dialect_);
    setManifestPrograms(m, programs_, plan_.start_s, plan_.duration_s);
    setManifestMachine(m, m_);
    m.tip_radius_mm = rt_;
    // The piece's stylus and its stated repeatability (L769: +-2 um, read as 2 sigma).
    m.probe_repeatability_2sigma_um = w_.probing.repeatability_mm * 1e3;
    m.part_name = w_.name;
    m.part_origin_mm = O_;
    m.material_name = w_.material.name;
    m.material_alpha_um_per_m_K = w_.material.alpha_um_per_m_K;
    auto& s = m.sw;
    s.experiment = e_->id;
    s.transition = e_->transition;
    s.transition_feed_mm_per_min = e_->transition_feed_mm_per_min;
    s.tool_runout_mm = e_->tool_runout_mm;
    s.tool_diameter_mm = tool_->diameter_mm;
    if (comp_) {
      // As the programs apply them: rounded to 0.1 um.
      s.compensation = comp_->steps;
      for (auto& c : s.compensation) {
        for (auto& v : c.wall_um) v = toProgram(v) * 1e3;
        c.floor_um = toProgram(c.floor_um) * 1e3;
      }
      s.compensation_file = comp_->file;
    }
    s.sizes_mm = sizes_;
    for (const auto& st : plan_.steps) {
      parts::ManifestStep x;
      x.step = st.step;
      x.feed_xy_mm_per_min = st.conditions.feed_xy_mm_per_min;
      x.feed_z_mm_per_min = st.conditions.feed_z_mm_per_min;
      x.spindle_speed_rpm = st.conditions.spindle_speed_rpm;
      x.start_s = st.start_s;
      x.end_s = st.end_s;
      x.temp_state_min = st.temp_state_min;
      s.steps.push_back(x);
    }
    s.cmm = w_.cmm;
    s.cmm_plan = files_.cmm_points;
    setFeatureCutTimes(m);
    const std::size_t pr = programs_.size() - 1;
    m.cycles = 1;
    m.gap_s = 0;
    m.cycle_time_s = plan_.duration_s[pr];
    m.cycle_start_s = {plan_.start_s[pr]};
  }

  std::string cmmCsv() const {
    return cmmPointsCsv({"probeloop plan: CMM points of " + w_.name + ", experiment " + e_->id +
                             " - nominal surface points and outward unit normals,",
                         "part frame at 20 C (origin at a corner of the top step in its top face, X and Y along its walls), mm"},
                        cmm_);
  }

  const SteppedWorkpiece& w_;
  const parts::Machine& m_;
  parts::Dialect dialect_;
  SwFiles files_;
  const parts::SwExperiment* e_ = nullptr;
  std::vector<double> sizes_;
  const parts::SwCompensation* comp_ = nullptr;
  // Compensation (Ch. 6): wall i of step k (XP, XN, YP, YN) moved inward by its predicted
  // outward error; the step's floor raised by its predicted depth error. mm.
  // Rounded to the programs' 0.1 um (4 decimals in mm), so that the material model and the
  // written coordinates agree.
  static double toProgram(double um) { return std::round(um * 10.0) * 1e-4; }
  double wallShift(std::size_t k, int i) const { return comp_ ? toProgram(comp_->steps[k].wall_um[static_cast<std::size_t>(i)]) : 0.0; }
  double floorShift(std::size_t k) const { return comp_ ? toProgram(comp_->steps[k].floor_um) : 0.0; }
  std::vector<parts::NominalFeature> features_;
  Vector3d O_;
  const parts::CuttingTool* tool_ = nullptr;
  double r_ = 0, rt_ = 0, c_ = 0, step_ = 0, z_clear_ = 0;
  Vector2d pos_ = Vector2d::Zero();  // current XY relative to the steps' centre (builder's view)
  Material material_;
  std::vector<std::vector<Material>> states_;  // per program, per op: the material the op moves in
  std::vector<std::size_t> step_first_op_, step_last_op_;
  std::vector<NotedProgram> programs_;
  std::vector<CmmRow> cmm_;
  parts::PlanManifest man_;
  SteppedWorkpiecePlan plan_;
};

}  // namespace

SwFiles swFiles(parts::Dialect d) {
  const std::string ext = d == parts::Dialect::LinuxCnc ? ".ngc" : ".nc";
  SwFiles f;
  f.roughing = "roughing" + ext;
  f.finishing = "finishing" + ext;
  f.probing = "probing" + ext;
  return f;
}

SteppedWorkpiecePlan planSteppedWorkpiece(const SteppedWorkpiece& w, const std::string& experiment, const parts::Machine& m,
                                          parts::Dialect dialect, const parts::SwCompensation* compensation) {
  return Builder(w, experiment, m, dialect, compensation).build();
}

std::string swProgramText(const NotedProgram& p, parts::Dialect dialect) {
  return dialect == parts::Dialect::LinuxCnc ? gcode::writeLinuxCnc(p.program) : gcode::writeFanucMacroB(p.program);
}

}  // namespace probeloop::planner
