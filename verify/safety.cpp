#include "verify/safety.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "gcode/interpreter.hpp"
#include "parts/stepped_workpiece.hpp"
#include "parts/thermal_test_piece.hpp"

namespace probeloop::verify {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

// --- bodies -----------------------------------------------------------------------------

// A vertical cylinder: a solid on the table (stem, obstacle) or a part of a tool.
struct Cyl {
  Vector2d c = Vector2d::Zero();
  double r = 0, z0 = 0, z1 = 0;
  std::string name;
};
struct Ball {
  Vector3d c = Vector3d::Zero();
  double r = 0;
  std::string name;
};

double pointCyl(const Vector3d& p, const Vector2d& c, double r, double z0, double z1) {
  const double dr = std::max((p.head<2>() - c).norm() - r, 0.0);
  const double dz = std::max({z0 - p.z(), p.z() - z1, 0.0});
  return std::hypot(dr, dz);
}
double cylCyl(const Vector2d& a, double ra, double a0, double a1, const Cyl& b) {
  const double dh = std::max((a - b.c).norm() - ra - b.r, 0.0);
  const double dz = std::max({a0 - b.z1, b.z0 - a1, 0.0});
  return std::hypot(dh, dz);
}

// A part of a tool, relative to its tip (the tool tip or the stylus-tip centre).
struct ToolPart {
  std::string name;
  bool ball = false;
  double r = 0, dz0 = 0, dz1 = 0;
  bool cuts = false;  // the fluted length of a cutter
};
struct Tool {
  int number = 0;
  bool probe = false;
  bool cutter = false;
  double length = 0;
  std::vector<ToolPart> parts;
  double lowest() const { return probe ? -parts.front().r : 0.0; }
  double maxRadius() const {
    double r = 0;
    for (const auto& p : parts) r = std::max(r, p.r);
    return r;
  }
  // The widest part that reaches below height `h` above the tip.
  double radiusBelow(double h) const {
    double r = 0;
    for (const auto& p : parts)
      if ((p.ball ? -p.r : p.dz0) < h) r = std::max(r, p.r);
    return r;
  }
};

// --- material: a height field in the table frame ----------------------------------------------

class HeightField {
 public:
  HeightField() = default;
  HeightField(const Vector2d& lo, const Vector2d& hi, double cell, double bottom) : lo_(lo), cell_(cell), bottom_(bottom) {
    nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / cell)));
    ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / cell)));
    top_.assign(static_cast<std::size_t>(nx_) * ny_, -kInf);
    row_max_.assign(static_cast<std::size_t>(ny_), -kInf);
    row_dirty_.assign(static_cast<std::size_t>(ny_), 1);
  }
  bool empty() const { return top_.empty(); }
  Vector2d centre(int i, int j) const { return lo_ + Vector2d((i + 0.5) * cell_, (j + 0.5) * cell_); }
  double& at(int i, int j) { return top_[static_cast<std::size_t>(j) * nx_ + i]; }
  double at(int i, int j) const { return top_[static_cast<std::size_t>(j) * nx_ + i]; }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double bottom() const { return bottom_; }
  double cell() const { return cell_; }
  long version() const { return version_; }
  // Cuts only lower cells, a few rows at a time, and every distance query asks for the top:
  // the rows a cut changed are re-scanned, not the whole field (that was most of `plan`'s
  // time on the thermal test piece).
  double maxTop() const {
    if (dirty_) {
      max_top_ = -kInf;
      for (int j = 0; j < ny_; ++j) {
        if (row_dirty_[j]) {
          double m = -kInf;
          for (int i = 0; i < nx_; ++i) m = std::max(m, at(i, j));
          row_max_[j] = m;
          row_dirty_[j] = 0;
        }
        max_top_ = std::max(max_top_, row_max_[j]);
      }
      dirty_ = false;
    }
    return max_top_;
  }
  // Cells of rows j0..j1 changed.
  void touched(int j0, int j1) {
    for (int j = j0; j <= j1; ++j) row_dirty_[j] = 1;
    dirty_ = true;
    ++version_;
  }

  // Cells whose centres lie within `reach` of xy.
  template <class F>
  void around(const Vector2d& xy, double reach, F f) const {
    if (empty()) return;
    const int i0 = std::max(0, static_cast<int>(std::floor((xy.x() - reach - lo_.x()) / cell_)));
    const int i1 = std::min(nx_ - 1, static_cast<int>(std::floor((xy.x() + reach - lo_.x()) / cell_)));
    const int j0 = std::max(0, static_cast<int>(std::floor((xy.y() - reach - lo_.y()) / cell_)));
    const int j1 = std::min(ny_ - 1, static_cast<int>(std::floor((xy.y() + reach - lo_.y()) / cell_)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const double t = at(i, j);
        if (t == -kInf) continue;
        f(centre(i, j), t);
      }
  }

  // Lower bound of the distance from a vertical cylinder to the material, at most `cap`.
  double distCyl(const Vector2d& xy, double r, double z0, double z1, double cap, double tol) const {
    if (empty() || z0 - maxTop() + tol >= cap || bottom_ - z1 >= cap) return cap;
    double best = cap;
    around(xy, r + cap, [&](const Vector2d& q, double top) {
      const double dh = std::max((q - xy).norm() - (r - tol), 0.0);
      if (dh >= best) return;
      const double dz = std::max({bottom_ - z1, z0 - top + tol, 0.0});
      best = std::min(best, std::hypot(dh, dz));
    });
    return best;
  }
  double distBall(const Vector3d& c, double r, double cap, double tol) const {
    if (empty() || c.z() - r - maxTop() + tol >= cap) return cap;
    double best = cap;
    around(c.head<2>(), r + cap, [&](const Vector2d& q, double top) {
      const double dzs = std::max({bottom_ - c.z(), c.z() - top, 0.0});
      best = std::min(best, std::max(0.0, std::hypot((q - c.head<2>()).norm(), dzs) - r + tol));
    });
    return best;
  }

  // Everything above z within r of the segment a-b goes (a vertical flat end mill).
  void cut(const Vector2d& a, const Vector2d& b, double r, double z) {
    if (empty() || z >= maxTop()) return;
    const Vector2d mid = (a + b) / 2;
    const double reach = (b - a).norm() / 2 + r;
    const Vector2d ab = b - a;
    const double L2 = ab.squaredNorm();
    bool changed = false;
    const int i0 = std::max(0, static_cast<int>(std::floor((mid.x() - reach - lo_.x()) / cell_)));
    const int i1 = std::min(nx_ - 1, static_cast<int>(std::floor((mid.x() + reach - lo_.x()) / cell_)));
    const int j0 = std::max(0, static_cast<int>(std::floor((mid.y() - reach - lo_.y()) / cell_)));
    const int j1 = std::min(ny_ - 1, static_cast<int>(std::floor((mid.y() + reach - lo_.y()) / cell_)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        double& t = at(i, j);
        if (t <= z) continue;
        const Vector2d q = centre(i, j);
        const double s = L2 > 0 ? std::clamp((q - a).dot(ab) / L2, 0.0, 1.0) : 0.0;
        if ((q - (a + s * ab)).norm() > r) continue;
        t = z <= bottom_ ? -kInf : z;
        changed = true;
      }
    if (changed) touched(j0, j1);
  }

  // The largest distance from `axis` of material that reaches above z.
  double envelope(const Vector2d& axis, double z) const {
    double r = -kInf;
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i)
        if (at(i, j) > z) r = std::max(r, (centre(i, j) - axis).norm() + cell_ * 0.7072);
    return r;
  }

 private:
  Vector2d lo_ = Vector2d::Zero();
  double cell_ = 0.5, bottom_ = 0;
  int nx_ = 0, ny_ = 0;
  std::vector<double> top_;
  mutable std::vector<double> row_max_;  // largest top of each row
  mutable std::vector<char> row_dirty_;  // rows changed since their maximum was taken
  mutable double max_top_ = -kInf;
  mutable bool dirty_ = true;
  long version_ = 0;
};

struct Scene {
  std::vector<Ball> spheres;
  std::vector<Cyl> cyls;
  double table_z = 0;
  HeightField material;
  std::string material_name;
  double clearance = 0;  // above the highest body
  double staticTop() const {
    double t = -kInf;
    for (const auto& s : spheres) t = std::max(t, s.c.z() + s.r);
    for (const auto& c : cyls) t = std::max(t, c.z1);
    return t;
  }
  double top() const { return std::max(staticTop(), material.maxTop()); }
  double clearancePlane() const { return top() + clearance; }
};

struct Hit {
  double d = kInf;
  std::string part, solid;
};

enum class Parts { All, TipOnly, ExceptTip };

std::string fmt(double v, int dec = 3) { return formatNumber(std::fabs(v) < 0.5 * std::pow(10.0, -dec) ? 0.0 : v, dec); }
std::string xyz(const Vector3d& p) { return "X" + fmt(p.x()) + " Y" + fmt(p.y()) + " Z" + fmt(p.z()); }

// --- the checking machine --------------------------------------------------------------

struct Interrupted {
  std::string event;
};

class Checker : public gcode::MachineInterface, public gcode::ProbeBranching {
 public:
  Checker(const parts::Machine& m, const parts::TestPiece& piece, const Options& o) : m_(m), o_(o) {
    buildTools(piece);
    buildScene(piece);
    pos_.xyz_mm = Vector3d(std::clamp(m.c_axis_centre_mm.x(), m.x.min_mm, m.x.max_mm),
                           std::clamp(m.c_axis_centre_mm.y(), m.y.min_mm, m.y.max_mm), m.z.max_mm);
  }

  std::vector<Finding> findings;
  std::string file;
  const Scene& scene() const { return scene_; }
  const std::map<int, Tool>& tools() const { return tools_; }

  // The machine's state (restored after each probe branch).
  struct State {
    gcode::MachinePosition pos;
    int tool = 0;
    double rpm = 0;
    int line = 0;
  };
  State state() const { return {pos_, tool_, rpm_, line_}; }
  void restore(const State& s) {
    pos_ = s.pos;
    tool_ = s.tool;
    rpm_ = s.rpm;
    line_ = s.line;
  }

  // A probe move whose other outcome does not stop the program: what the program went on to.
  struct Unprotected {
    int line = 0;
    long probe = 0;  // index of the probe move in the program's run
    bool contact = false;  // the nominal outcome
    std::string went_on;
    Vector3d tip = Vector3d::Zero();
  };
  // Starts a program's run: the probe lines branched so far are forgotten.
  void startProgram() {
    branched_lines_.clear();
    unprotected_.clear();
    probes_ = 0;
  }
  const std::vector<Unprotected>& unprotected() const { return unprotected_; }
  long probes() const { return probes_; }

  // --- ProbeBranching: protection ---
  // Each probe line's first execution, with its outcome inverted, must stop the program before
  // anything else happens: the branch runs on from the probe move (the interpreter's state
  // copied there), and the first event that is not a stop interrupts it. One run of the
  // program and one short branch per probe line: linear in the program's length.
  void atProbe(const gcode::ProbeOutcome& nominal, const RunWith& run_with) override {
    if (!branched_lines_.insert(line_).second) return;
    gcode::ProbeOutcome other = nominal;
    if (nominal.contact) {
      other.contact = false;
      other.stop = probe_to_;
    } else {
      other.contact = true;
      other.stop = probe_from_;
      // Half-way; 0.5 a + 0.5 b stays finite where b - a would overflow.
      other.stop.xyz_mm = 0.5 * probe_from_.xyz_mm + 0.5 * probe_to_.xyz_mm;
    }
    const State saved = state();
    Unprotected u{line_, probes_ - 1, nominal.contact, "", tip(nominal.stop)};
    bool stopped = false;
    replay_ = true;
    pos_ = other.stop;
    try {
      run_with(other);
      u.went_on = "the program's end";
    } catch (const Interrupted& i) {
      u.went_on = i.event;
    } catch (const SafetyError&) {
      stopped = true;
    } catch (...) {
      replay_ = false;
      restore(saved);
      throw;
    }
    replay_ = false;
    restore(saved);
    if (!stopped) unprotected_.push_back(std::move(u));
  }

  // A coordinate that is not a number compares false with every limit: a move to it is never
  // checked, it is refused (the interpreter refuses it first; this is the second guard). The
  // interpreter adds the file:line, and `check` exits 2: the program cannot be evaluated.
  static const gcode::MachinePosition& requireFinite(const gcode::MachinePosition& to) {
    if (!to.xyz_mm.allFinite() || !std::isfinite(to.a_deg) || !std::isfinite(to.b_deg) || !std::isfinite(to.c_deg))
      throw InputError("", 0, "a move to a coordinate that is not a finite number: the program cannot be checked");
    return to;
  }

  // --- MachineInterface ---
  gcode::MachinePosition start() const override { return pos_; }
  void atLine(int line) override { line_ = line; }
  void rapid(const gcode::MachinePosition& to) override { move(requireFinite(to), false, 0); }
  void feed(const gcode::MachinePosition& to, double f) override { move(requireFinite(to), true, f); }
  gcode::ProbeOutcome probe(const gcode::MachinePosition& to, double, gcode::ProbeMode) override {
    requireFinite(to);
    event("a probe move");
    const auto r = probeNominal(to);
    ++probes_;
    probe_from_ = pos_;
    probe_to_ = to;
    pos_ = r.stop;
    return r;
  }
  void dwell(double) override { event("a dwell"); }
  // externalVariable and analogInput keep MachineInterface's defaults on purpose: the program is
  // checked as it runs with nothing writing the sphere cycle's live interval (Fanuc #500,
  // LinuxCNC analog input 0), so its wait loop is not entered. Any value written would only add
  // dwells, which move nothing; one that never drops to 0 would be an endless loop by design.
  void toolChange(int tool) override {
    event("a tool change");
    toolOf(tool);
    tool_ = tool;
  }
  double toolLength(int tool) const override { return toolOf(tool).length; }
  void spindle(double rpm) override {
    event(rpm != 0 ? "the spindle starting" : "the spindle stopping");
    rpm_ = rpm;
    if (replay_ || rpm == 0) return;
    if (tool_ == m_.probe.tool)
      add("spindle-with-probe", (rpm > 0 ? "M3" : "M4") + std::string(" S") + fmt(std::fabs(rpm), 0) +
                                    " with the probe (T" + std::to_string(tool_) + ") in the spindle",
          tip(pos_), "no spindle rotation with a touch probe");
  }
  void coolant(bool) override { event("coolant"); }
  void openLog(const std::string&) override { event("opening the log"); }
  void log(const std::string&) override { event("a log line (a point logged)"); }
  void closeLog() override { event("closing the log"); }

  void add(const std::string& rule, const std::string& what, const Vector3d& where, const std::string& limit) {
    if (replay_) return;
    if (!seen_.insert({file, line_, rule}).second) return;  // loops repeat a finding: once per line
    findings.push_back({file, line_, rule, what, where, limit});
  }
  void addAt(int line, const std::string& rule, const std::string& what, const Vector3d& where, const std::string& limit) {
    if (!seen_.insert({file, line, rule}).second) return;
    findings.push_back({file, line, rule, what, where, limit});
  }

  Vector3d tip(const gcode::MachinePosition& p) const { return p.xyz_mm - Vector3d(0, 0, toolOf(tool_).length); }

 private:
  const parts::Machine& m_;
  Options o_;
  std::map<int, Tool> tools_;
  Scene scene_;
  gcode::MachinePosition pos_;
  int tool_ = -1;  // unknown at the start: nothing in the spindle is assumed
  double rpm_ = 0;
  int line_ = 0;
  // In a probe branch (after the inverted outcome): nothing is checked, the first event stops it.
  bool replay_ = false;
  long probes_ = 0;  // probe moves of this program's run so far
  gcode::MachinePosition probe_from_, probe_to_;  // the last probe move
  std::set<int> branched_lines_;
  std::vector<Unprotected> unprotected_;
  mutable long envelope_version_ = -1;  // the bodies' circle, for this state of the material
  mutable double envelope_ = 0;
  std::set<std::tuple<std::string, int, std::string>> seen_;
  std::set<std::tuple<double, double, double, int, long, double, double>> turned_;  // rotary sweeps already checked

  void event(const std::string& what) {
    if (replay_) throw Interrupted{what};
  }

  const Tool& toolOf(int n) const {
    static const Tool empty;
    if (n == -1 || n == m_.tool_change.empty_tool) return empty;
    const auto it = tools_.find(n);
    if (it == tools_.end())
      throw InputError("", 0, "T" + std::to_string(n) + " is neither the machine's probe (T" + std::to_string(m_.probe.tool) +
                                  ") nor a tool of the part description");
    return it->second;
  }

  void buildTools(const parts::TestPiece& piece) {
    Tool p;
    p.number = m_.probe.tool;
    p.probe = true;
    p.length = m_.probe.length_mm;
    // A piece probed with a stylus of its own (the stepped workpiece's 2 mm ball): that ball,
    // and a shaft no thicker than 0.75 x it.
    double tip = m_.probe.tip_diameter_mm, shaft = m_.probe.stylus_diameter_mm;
    if (piece.stock && piece.stock->probe_tip_diameter_mm > 0) {
      tip = piece.stock->probe_tip_diameter_mm;
      shaft = std::min(shaft, 0.75 * tip);
    }
    p.parts = {{"stylus tip", true, tip / 2, 0, 0, false},
               {"stylus shaft", false, shaft / 2, 0, m_.probe.stylus_length_mm, false},
               {"probe body", false, m_.probe.body_diameter_mm / 2, m_.probe.stylus_length_mm, m_.probe.length_mm, false}};
    tools_[p.number] = p;
    if (!piece.stock) return;
    for (const auto& t : piece.stock->tools) {
      Tool c;
      c.number = t.number;
      c.cutter = true;
      c.length = t.length_mm;
      const double r = t.diameter_mm / 2;
      const double flutes = std::min(t.flute_length_mm > 0 ? t.flute_length_mm : t.stickout_mm, t.length_mm);
      const double stick = std::clamp(t.stickout_mm > 0 ? t.stickout_mm : flutes, flutes, t.length_mm);
      c.parts.push_back({"cutter", false, r, 0, flutes, true});
      if (stick > flutes) c.parts.push_back({"shank", false, r, flutes, stick, false});
      if (t.length_mm > stick) c.parts.push_back({"holder", false, m_.tool_change.holder_diameter_mm / 2, stick, t.length_mm, false});
      tools_[c.number] = c;
    }
  }

  void buildScene(const parts::TestPiece& piece) {
    scene_.table_z = m_.table_surface_z_mm;
    scene_.clearance = 5;
    if (const auto* a = piece.sphereArtifact()) {
      const double th = a->angle_at_c0_deg * kPi / 180;
      const Vector3d c(m_.c_axis_centre_mm.x() + a->radius_from_axis_mm * std::cos(th),
                       m_.c_axis_centre_mm.y() + a->radius_from_axis_mm * std::sin(th),
                       m_.table_surface_z_mm + a->centreHeightAboveTable());
      scene_.spheres.push_back({c, a->sphereRadius(), "the sphere of the artifact"});
      scene_.cyls.push_back({c.head<2>(), a->stem_diameter_mm / 2, m_.table_surface_z_mm, c.z() - a->sphereRadius(),
                             "the artifact's stem"});
      scene_.clearance = a->clearance_mm;
      return;
    }
    if (!piece.stock) return;
    const parts::Workpiece& w = *piece.stock;
    Vector3d origin = w.frame_origin_mm;
    if (const auto* t = piece.thermalTestPiece()) {
      origin = parts::partOriginOnMachine(*t, m_.c_axis_centre_mm, m_.table_surface_z_mm);
      scene_.clearance = t->probing.clearance_mm;
    } else if (const auto* sw = piece.steppedWorkpiece()) {
      origin = parts::steppedWorkpieceOrigin(*sw, m_);
      scene_.clearance = sw->machining.clearance_mm;
    }
    for (const auto& o : w.obstacles)
      scene_.cyls.push_back({o.centre_mm + origin.head<2>(), o.radius_mm, o.z_min_mm + origin.z(), o.z_max_mm + origin.z(),
                             "the " + o.name});
    const Vector3d lo = w.stock_min_mm + origin, hi = w.stock_max_mm + origin;
    scene_.material = HeightField(lo.head<2>(), hi.head<2>(), o_.cell_mm, lo.z());
    scene_.material_name = "the stock";
    const Vector2d cc = (lo.head<2>() + hi.head<2>()) / 2;
    const double cr = (hi.x() - lo.x()) / 2;
    auto& hf = scene_.material;
    for (int j = 0; j < hf.ny(); ++j)
      for (int i = 0; i < hf.nx(); ++i) {
        const Vector2d q = hf.centre(i, j);
        const bool in = w.cylindrical ? (q - cc).norm() <= cr
                                      : q.x() >= lo.x() && q.x() <= hi.x() && q.y() >= lo.y() && q.y() <= hi.y();
        if (!in) continue;
        double top = hi.z();
        for (const auto& h : w.holes)  // only a hole open at the top shows from above
          if (h.z_max_mm + origin.z() >= hi.z() - 1e-9 && (q - h.centre_mm - origin.head<2>()).norm() <= h.radius_mm)
            top = std::min(top, h.z_min_mm + origin.z() <= lo.z() + 1e-9 ? -kInf : h.z_min_mm + origin.z());
        hf.at(i, j) = top;
      }
    hf.touched(0, hf.ny() - 1);
  }

  // --- geometry of a pose ---

  Vector3d tableFrame(const Vector3d& p, double c_deg) const {
    if (!m_.c.present) return p;
    const Vector2d xy = m_.c_axis_centre_mm +
                        parts::unturnedByTable(p.head<2>() - m_.c_axis_centre_mm, c_deg, m_.c.positive_is_clockwise);
    return Vector3d(xy.x(), xy.y(), p.z());
  }

  // Distance of the tool at tip position t (table frame) to everything; at most cap for material.
  Hit distance(const Tool& tool, const Vector3d& t, Parts which, bool cutting, double cap) const {
    Hit best;
    auto take = [&](double d, const std::string& part, const std::string& solid) {
      if (d < best.d) best = {d, part, solid};
    };
    for (std::size_t k = 0; k < tool.parts.size(); ++k) {
      const ToolPart& p = tool.parts[k];
      if (which == Parts::TipOnly && !(p.ball)) continue;
      if (which == Parts::ExceptTip && p.ball) continue;
      if (p.ball) {
        for (const auto& s : scene_.spheres) take((t - s.c).norm() - p.r - s.r, p.name, s.name);
        for (const auto& c : scene_.cyls) take(pointCyl(t, c.c, c.r, c.z0, c.z1) - p.r, p.name, c.name);
        take(t.z() - p.r - scene_.table_z, p.name, "the table");
        take(scene_.material.distBall(t, p.r, cap, o_.tolerance_mm), p.name, scene_.material_name);
      } else {
        const Vector2d xy = t.head<2>();
        const double z0 = t.z() + p.dz0, z1 = t.z() + p.dz1;
        for (const auto& s : scene_.spheres) take(pointCyl(s.c, xy, p.r, z0, z1) - s.r, p.name, s.name);
        for (const auto& c : scene_.cyls) take(cylCyl(xy, p.r, z0, z1, c), p.name, c.name);
        take(z0 - scene_.table_z, p.name, "the table");
        if (!(cutting && p.cuts))
          take(scene_.material.distCyl(xy, p.r, z0, z1, cap, o_.tolerance_mm), p.name, scene_.material_name);
      }
    }
    return best;
  }

  struct Motion {
    Vector3d a, b;  // tip, machine coordinates
    double c0 = 0, c1 = 0;
  };
  Vector3d at(const Motion& mo, double s) const {
    return tableFrame(mo.a + s * (mo.b - mo.a), mo.c0 + s * (mo.c1 - mo.c0));
  }
  double speed(const Motion& mo, const Tool& tool) const {
    const double rho = std::max((mo.a.head<2>() - m_.c_axis_centre_mm).norm(), (mo.b.head<2>() - m_.c_axis_centre_mm).norm());
    return (mo.b - mo.a).norm() + std::fabs(mo.c1 - mo.c0) * kPi / 180 * (rho + (mo.b - mo.a).norm() + tool.maxRadius());
  }

  struct Sweep {
    bool hit = false;
    double s_hit = 1;
    Hit h;
    double d_start = kInf, d_min = kInf;
    double s_min = 0;
  };
  // Conservative advancement: the distance bounds how far the tool may move unchecked.
  Sweep sweep(const Tool& tool, const Motion& mo, Parts which, bool cutting, double cap, double min_step) const {
    Sweep r;
    const double v = speed(mo, tool);
    double s = 0;
    for (;;) {
      const Hit h = distance(tool, at(mo, s), which, cutting, cap);
      const double d = std::min(h.d, cap);
      if (s == 0) r.d_start = d;
      if (d < r.d_min) {
        r.d_min = d;
        r.s_min = s;
      }
      if (h.d <= 1e-9) {
        r.hit = true;
        r.s_hit = s;
        r.h = h;
        return r;
      }
      if (s >= 1 || v < 1e-12) return r;
      s = std::min(1.0, s + std::max(d, min_step) / v);
    }
  }

  void checkTravel(const gcode::MachinePosition& to) {
    const parts::LinearAxis* ax[3] = {&m_.x, &m_.y, &m_.z};
    const char* names = "XYZ";
    for (int i = 0; i < 3; ++i)
      if (to.xyz_mm(i) < ax[i]->min_mm - 1e-6 || to.xyz_mm(i) > ax[i]->max_mm + 1e-6)
        add("travel",
            std::string(1, names[i]) + " = " + fmt(to.xyz_mm(i)) + " mm (gauge line) is outside the " + names[i] + " travel",
            tip(to), std::string(1, names[i]) + " travel [" + fmt(ax[i]->min_mm) + ", " + fmt(ax[i]->max_mm) + "] mm of " + m_.file);
    auto rotary = [&](const parts::RotaryAxis& a, double v, double was, const char* n) {
      if (!a.present) {
        if (std::fabs(v - was) > 1e-9 || std::fabs(v) > 1e-9)
          add("travel", std::string(n) + " = " + fmt(v) + " deg: the machine has no " + n + " axis", tip(to),
              std::string("no ") + n + " axis in " + m_.file);
        return;
      }
      if (!a.continuous && (v < a.min_deg - 1e-6 || v > a.max_deg + 1e-6))
        add("travel", std::string(n) + " = " + fmt(v) + " deg is outside the " + n + " travel", tip(to),
            std::string(n) + " travel [" + fmt(a.min_deg) + ", " + fmt(a.max_deg) + "] deg of " + m_.file);
    };
    rotary(m_.a, to.a_deg, pos_.a_deg, "A");
    rotary(m_.b, to.b_deg, pos_.b_deg, "B");
    rotary(m_.c, to.c_deg, pos_.c_deg, "C");
  }

  std::string moveName(bool feed) const { return feed ? "feed move (G1)" : "rapid move (G0)"; }

  void move(const gcode::MachinePosition& to, bool is_feed, double) {
    event(is_feed ? "a feed move" : "a rapid move");
    if (replay_) {
      pos_ = to;
      return;
    }
    checkTravel(to);
    const Tool& tool = toolOf(tool_);
    Motion mo{tip(pos_), tip(to), pos_.c_deg, to.c_deg};
    const bool rotary = std::fabs(to.c_deg - pos_.c_deg) > 1e-9;
    const bool a_moves = std::fabs(to.a_deg - pos_.a_deg) > 1e-9;
    const bool tilt = std::fabs(to.b_deg - pos_.b_deg) > 1e-9 || a_moves;
    const char* tilt_name = std::fabs(to.b_deg - pos_.b_deg) > 1e-9 ? "B" : "A";
    const bool cutting = is_feed && tool.cutter && rpm_ != 0;
    // A table turning many times under a still tool sweeps the same ring: one turn.
    if (rotary && (mo.b - mo.a).norm() < 1e-9 && std::fabs(mo.c1 - mo.c0) > 360)
      mo.c1 = mo.c0 + (mo.c1 > mo.c0 ? 360.0 : -360.0);
    const double plane = scene_.clearancePlane();
    const double low = std::min(mo.a.z(), mo.b.z()) + tool.lowest();

    if (!tool.parts.empty()) {
      // The same full turn at the same place on the same material: checked once.
      const bool turn = rotary && (mo.b - mo.a).norm() < 1e-9 && std::fabs(mo.c1 - mo.c0) >= 360 - 1e-9;
      const auto key = std::make_tuple(mo.a.x(), mo.a.y(), mo.a.z(), tool_, scene_.material.version(), cutting ? 1.0 : 0.0, 0.0);
      if (!turn || turned_.insert(key).second) {
        const Sweep s = sweep(tool, mo, Parts::All, cutting, 5.0, 0.05);
        if (s.hit)
          add("collision",
              moveName(is_feed) + (cutting ? " (cutting)" : "") + ": the " + s.h.part + " " +
                  (tool.probe ? "of the probe" : "of T" + std::to_string(tool_)) + " meets " + s.h.solid,
              mo.a + s.s_hit * (mo.b - mo.a), "clear of " + s.h.solid + (s.h.solid == scene_.material_name ? " (height field, " + fmt(o_.cell_mm, 2) + " mm cells, tolerance " + fmt(o_.tolerance_mm, 2) + " mm)" : ""));
        if (tool.probe && low < plane - 1e-3) {
          const double cap = std::max(scene_.clearance, 5.0);
          const Sweep a = sweep(tool, mo, Parts::All, false, cap, 0.25);
          const double tol = scene_.material.empty() ? 0.01 : o_.cell_mm;
          if (!a.hit && a.d_min < a.d_start - tol && a.d_min < cap)
            add("positioning-unprotected",
                moveName(is_feed) + " with the probe below the clearance plane closes in on the part from " + fmt(a.d_start) +
                    " mm to " + fmt(a.d_min) + " mm without protection (G38.3 / G31 with a check)",
                mo.a + a.s_min * (mo.b - mo.a),
                "below Z " + fmt(plane) + " (tip's lowest point) the probe approaches only in protected moves");
        }
      }
      if (cutting) removeMaterial(tool, mo);
    }
    if ((rotary || tilt) && !cutting && low < plane - 1e-3) {
      const double r_tool = tool.radiusBelow(plane - std::min(mo.a.z(), mo.b.z()));
      const double rho = std::min((mo.a.head<2>() - m_.c_axis_centre_mm).norm(), (mo.b.head<2>() - m_.c_axis_centre_mm).norm());
      const double env = envelope();
      if (tilt || rho - r_tool < env)
        add("rotary-below-clearance",
            std::string(tilt ? "B" : "C") + " moves from " + fmt(tilt ? pos_.b_deg : pos_.c_deg) + " to " +
                fmt(tilt ? to.b_deg : to.c_deg) + " deg with the " + (tool.probe ? "probe" : "tool") + "'s lowest point at Z " +
                fmt(low) + (tilt ? "" : ", " + fmt(rho - r_tool) + " mm from the C axis, inside the " + fmt(env) + " mm circle the table's bodies sweep"),
            mo.a, "clearance plane Z " + fmt(plane) + " (" + fmt(scene_.clearance) + " mm above the highest body)");
    }
    pos_ = to;
  }

  // The circle every body on the table sweeps when C turns (whatever its height: below the
  // clearance plane the margin is the plane's, not the bodies' tops).
  double envelope() const {
    if (envelope_version_ == scene_.material.version()) return envelope_;
    envelope_version_ = scene_.material.version();
    double& env = envelope_;
    env = scene_.material.envelope(m_.c_axis_centre_mm, -kInf);
    for (const auto& s : scene_.spheres) env = std::max(env, (s.c.head<2>() - m_.c_axis_centre_mm).norm() + s.r);
    for (const auto& c : scene_.cyls) env = std::max(env, (c.c - m_.c_axis_centre_mm).norm() + c.r);
    return env;
  }

  void removeMaterial(const Tool& tool, const Motion& mo) {
    const ToolPart* cutter = nullptr;
    for (const auto& p : tool.parts)
      if (p.cuts) cutter = &p;
    if (!cutter || scene_.material.empty()) return;
    const double v = speed(mo, tool);
    const bool straight = std::fabs(mo.c1 - mo.c0) < 1e-9;
    const int n = straight ? std::max(1, static_cast<int>(std::ceil(std::fabs(mo.b.z() - mo.a.z()) / (o_.cell_mm / 2))))
                           : std::max(1, static_cast<int>(std::ceil(v / (o_.cell_mm / 2))));
    Vector3d p0 = at(mo, 0);
    for (int k = 1; k <= n; ++k) {
      const Vector3d p1 = at(mo, static_cast<double>(k) / n);
      scene_.material.cut(p0.head<2>(), p1.head<2>(), cutter->r, std::max(p0.z(), p1.z()));
      p0 = p1;
    }
  }

  gcode::ProbeOutcome probeNominal(const gcode::MachinePosition& to) {
    checkTravel(to);
    gcode::ProbeOutcome r;
    r.stop = to;
    const Tool& tool = toolOf(tool_);
    const Motion mo{tip(pos_), tip(to), pos_.c_deg, to.c_deg};
    if (tool.parts.empty()) return r;
    const Sweep t = tool.probe ? sweep(tool, mo, Parts::TipOnly, false, 5.0, 0.002) : Sweep{};
    Motion before = mo;
    if (t.hit) {
      r.contact = true;
      // The probe latches at the contact; the stop is taken 0.02 mm back along the move (the
      // advancement may step up to 0.002 mm into the body), so a retreat starts clear.
      const double len = (mo.b - mo.a).norm();
      const double s_stop = len > 0 ? std::max(0.0, t.s_hit - 0.02 / len) : 0.0;
      r.stop.xyz_mm = pos_.xyz_mm + s_stop * (to.xyz_mm - pos_.xyz_mm);
      r.stop.c_deg = pos_.c_deg + s_stop * (to.c_deg - pos_.c_deg);
      before.b = mo.a + t.s_hit * (mo.b - mo.a);
      before.c1 = r.stop.c_deg;
      const double past = (1 - t.s_hit) * (mo.b - mo.a).norm();
      if (past > m_.probe.max_overtravel_mm + 1e-6)
        add("probe-unbounded",
            "probing move goes on " + fmt(past) + " mm past the contact with " + t.h.solid + " (at " + xyz(mo.a + t.s_hit * (mo.b - mo.a)) + ")",
            mo.b, "probe.max_overtravel " + fmt(m_.probe.max_overtravel_mm) + " mm of " + m_.file);
    }
    const Sweep o = sweep(tool, before, tool.probe ? Parts::ExceptTip : Parts::All, false, 5.0, 0.01);
    if (o.hit)
      add("collision",
          "probe move: the " + o.h.part + " meets " + o.h.solid + (tool.probe ? " before the stylus tip touches anything" : ""),
          mo.a + o.s_hit * (before.b - mo.a), "only the stylus tip may touch");
    return r;
  }
};

gcode::ProgramDialect dialectOf(const std::string& file, const parts::Machine& m) {
  const std::string ext = std::filesystem::path(file).extension().string();
  if (ext == ".ngc") return gcode::ProgramDialect::LinuxCnc;
  if (ext == ".nc" || ext == ".tap") return gcode::ProgramDialect::FanucMacroB;
  return m.dialect == parts::Dialect::LinuxCnc ? gcode::ProgramDialect::LinuxCnc : gcode::ProgramDialect::FanucMacroB;
}

// "<file>:<line>: <what>" -> line and what (a SafetyError of the interpreter).
std::pair<int, std::string> located(const std::string& file, const std::string& what) {
  const std::string pre = file + ":";
  if (what.rfind(pre, 0) != 0) return {0, what};
  std::size_t i = pre.size();
  int line = 0;
  while (i < what.size() && std::isdigit(static_cast<unsigned char>(what[i]))) line = line * 10 + (what[i++] - '0');
  if (i + 1 < what.size() && what[i] == ':') i += 2;
  return {line, what.substr(i)};
}

std::string modelText(const parts::Machine& m, const parts::TestPiece& piece, const Scene& sc, const std::map<int, Tool>& tools,
                      const Options& o) {
  std::ostringstream s;
  const Tool& probe = tools.at(m.probe.tool);
  s << "probe T" << m.probe.tool << ": tip ball d " << fmt(2 * probe.parts[0].r, 2) << " mm, stylus shaft d "
    << fmt(2 * probe.parts[1].r, 2) << " mm x " << fmt(m.probe.stylus_length_mm, 1) << " mm, body d "
    << fmt(m.probe.body_diameter_mm, 1) << " mm up to the gauge line (" << fmt(m.probe.length_mm, 1) << " mm); ";
  for (const auto& [n, t] : tools) {
    if (t.probe) continue;
    s << "T" << n << ":";
    for (const auto& p : t.parts) s << " " << p.name << " d " << fmt(2 * p.r, 2) << " mm " << fmt(p.dz0, 1) << ".." << fmt(p.dz1, 1);
    s << " mm above the tip; ";
  }
  for (const auto& b : sc.spheres) s << b.name << " d " << fmt(2 * b.r, 2) << " mm at " << xyz(b.c) << " (C 0); ";
  for (const auto& c : sc.cyls)
    s << c.name << " d " << fmt(2 * c.r, 2) << " mm Z " << fmt(c.z0) << ".." << fmt(c.z1) << " at X" << fmt(c.c.x()) << " Y" << fmt(c.c.y()) << "; ";
  if (!sc.material.empty())
    s << sc.material_name << " of " << piece.name << " as a height field of " << fmt(o.cell_mm, 2)
      << " mm cells, cut by the programs' own feed moves with the spindle on; ";
  s << "the table at Z " << fmt(sc.table_z) << "; clearance plane " << fmt(sc.clearance) << " mm above the highest body";
  return s.str();
}

}  // namespace

Report checkPrograms(const std::vector<ProgramText>& programs, const parts::Machine& machine, const parts::TestPiece& piece,
                     const Options& options) {
  Report rep;
  Checker ck(machine, piece, options);
  rep.model = modelText(machine, piece, ck.scene(), ck.tools(), options);
  for (const auto& p : programs) {
    rep.programs.push_back(p.file);
    ck.file = p.file;
    const auto dialect = dialectOf(p.file, machine);
    ck.startProgram();
    bool stopped_nominal = false;
    try {
      gcode::Interpreter in(dialect, p.file, p.text);
      in.run(ck, gcode::Interpreter::kMaxBlocks, &ck);
    } catch (const SafetyError& e) {
      stopped_nominal = true;
      const auto [line, what] = located(p.file, e.what());
      ck.addAt(line, "program-stops", "the program stops here on the nominal part: " + what, ck.tip(ck.start()),
               "a program runs to its end when nothing is out of place");
    }
    // Protection: each probe line's first move with its outcome inverted must stop the program
    // before anything else happens (tried in the run, ProbeBranching above).
    for (const auto& u : ck.unprotected()) {
      // A program that stopped on its last probe move: that move's outcome was already the
      // unexpected one (its finding is program-stops).
      if (stopped_nominal && u.probe + 1 == ck.probes()) continue;
      ck.addAt(u.line, "probe-unprotected",
               u.contact ? "measuring move: when the probe does not trigger the program goes on to " + u.went_on + " instead of stopping"
                         : "positioning probe move: when the probe touches something the program goes on to " + u.went_on +
                               " instead of stopping",
               u.tip, u.contact ? "no contact -> error (G38.2, or G31 with a check and #3000)"
                                : "contact -> ABORT / #3000 (G38.3 + #5070 check, or G31 with a check)");
    }
  }
  rep.findings = ck.findings;
  std::stable_sort(rep.findings.begin(), rep.findings.end(), [&](const Finding& a, const Finding& b) {
    const auto ia = std::find(rep.programs.begin(), rep.programs.end(), a.file) - rep.programs.begin();
    const auto ib = std::find(rep.programs.begin(), rep.programs.end(), b.file) - rep.programs.begin();
    return std::tie(ia, a.line) < std::tie(ib, b.line);
  });
  return rep;
}

std::string reportText(const Report& r) {
  std::ostringstream s;
  for (const auto& f : r.findings)
    s << f.file << ":" << f.line << ": " << f.rule << ": " << f.what << ", at " << xyz(f.where_mm) << " (mm), limit: " << f.limit
      << "\n";
  return s.str();
}

std::string reportJson(const Report& r) {
  nlohmann::ordered_json j;
  j["safe"] = r.safe();
  j["programs"] = r.programs;
  j["model"] = r.model;
  j["findings"] = nlohmann::ordered_json::array();
  for (const auto& f : r.findings)
    j["findings"].push_back({{"file", f.file},
                             {"line", f.line},
                             {"rule", f.rule},
                             {"what", f.what},
                             {"where_mm", {f.where_mm.x(), f.where_mm.y(), f.where_mm.z()}},
                             {"limit", f.limit}});
  return j.dump(2) + "\n";
}

}  // namespace probeloop::verify
