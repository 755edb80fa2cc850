// The safety verifier's checking machine (safety.hpp), shared by its files and internal to
// verify/: the bodies and tools it models (safety_scene.cpp), the machine the interpreter
// runs against with its travel, collision and probing rules (safety_checker.cpp), and the
// rotary moves: C turning under a still tool, the table tilting with A or B (the trunnion's or
// cradle's swing) and every move made while the table is tilted (safety_rotary.cpp).
//
// Frames: the scene is built in machine coordinates of the tip (tool tip or stylus-tip centre)
// with the table at A = B = C = 0, which is the table frame. A pose (tip, C, tilt angle q)
// maps a machine point into the table frame by undoing the tilt about its axis line, then the
// C turn (parts/machine_chain.hpp: the tilting body carries C; rotary directions follow
// RotaryAxis::positive_is_clockwise).
#pragma once
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "gcode/interpreter.hpp"
#include "parts/machine.hpp"
#include "parts/piece_kinds.hpp"
#include "verify/safety.hpp"

namespace probeloop::verify::detail {

using Eigen::Vector2d;
using Eigen::Vector3d;
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kPi = 3.14159265358979323846;

// --- bodies -----------------------------------------------------------------------------

// A vertical cylinder (table frame): a solid on the table (stem, obstacle) or a part of a tool.
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

double pointCyl(const Vector3d& p, const Vector2d& c, double r, double z0, double z1);
double cylCyl(const Vector2d& a, double ra, double a0, double a1, const Cyl& b);

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
  HeightField(const Vector2d& lo, const Vector2d& hi, double cell, double bottom);
  bool empty() const { return top_.empty(); }
  Vector2d centre(int i, int j) const { return lo_ + Vector2d((i + 0.5) * cell_, (j + 0.5) * cell_); }
  double& at(int i, int j) { return top_[static_cast<std::size_t>(j) * nx_ + i]; }
  double at(int i, int j) const { return top_[static_cast<std::size_t>(j) * nx_ + i]; }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double bottom() const { return bottom_; }
  double cell() const { return cell_; }
  long version() const { return version_; }
  Vector2d lo() const { return lo_; }
  Vector2d hi() const { return lo_ + Vector2d(nx_ * cell_, ny_ * cell_); }
  // Cuts only lower cells, a few rows at a time, and every distance query asks for the top:
  // the rows a cut changed are re-scanned, not the whole field (that was most of `plan`'s
  // time on the thermal test piece).
  double maxTop() const;
  // Cells of rows j0..j1 changed.
  void touched(int j0, int j1);
  // Lower bound of the distance from a vertical cylinder to the material, at most `cap`.
  double distCyl(const Vector2d& xy, double r, double z0, double z1, double cap, double tol) const;
  double distBall(const Vector3d& c, double r, double cap, double tol) const;
  // Everything above z within r of the segment a-b goes (a vertical flat end mill).
  void cut(const Vector2d& a, const Vector2d& b, double r, double z);
  // The largest distance from `axis` of material that reaches above z.
  double envelope(const Vector2d& axis, double z) const;

 private:
  // Cells whose centres lie within `reach` of xy (safety_scene.cpp only).
  template <class F>
  void around(const Vector2d& xy, double reach, F f) const;

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

// The tilting axis (A or B) where the machine locates it (b_axis / a_axis): its line through
// `point` along `direction`, about which +q turns the table right-handedly (direction = -X or
// -Y for an axis that turns clockwise seen from +X / +Y). Without a located line a tilting move
// is checked as before issue 33: refused below the clearance plane.
struct TiltAxis {
  char name = 0;          // 'A', 'B', or 0 (no tilting axis)
  bool located = false;
  Vector3d point = Vector3d::Zero(), direction = Vector3d::UnitY();
};
TiltAxis tiltAxisOf(const parts::Machine& m);

// How close a tool may come to the bodies a tilting table carries while it swings (and the
// table itself): a near miss, not a clearance (positioning keeps the piece's clearance plane).
inline constexpr double kSwingMarginMm = 2.0;
// The table as the verifier models it under a tilt: a disc on the C axis, its top the table
// surface, this deep, of radius the farthest body's distance from C plus kTableRimMm (the
// machine description gives no table diameter).
inline constexpr double kTableDepthMm = 300.0;
inline constexpr double kTableRimMm = 10.0;

struct Hit {
  double d = kInf;
  std::string part, solid;
};

enum class Parts { All, TipOnly, ExceptTip };

std::string fmt(double v, int dec = 3);
std::string xyz(const Vector3d& p);

struct Interrupted {
  std::string event;
};

class Checker : public gcode::MachineInterface, public gcode::ProbeBranching {
 public:
  Checker(const parts::Machine& m, const parts::TestPiece& piece, const Options& o);

  std::vector<Finding> findings;
  std::string file;
  const Scene& scene() const { return scene_; }
  const std::map<int, Tool>& tools() const { return tools_; }
  const TiltAxis& tiltAxis() const { return tilt_; }
  double tableRadius() const { return table_radius_; }

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
  void atProbe(const gcode::ProbeOutcome& nominal, const RunWith& run_with) override;

  // A coordinate that is not a number compares false with every limit: a move to it is never
  // checked, it is refused (the interpreter refuses it first; this is the second guard). The
  // interpreter adds the file:line, and `check` exits 2: the program cannot be evaluated.
  static const gcode::MachinePosition& requireFinite(const gcode::MachinePosition& to);

  // --- MachineInterface ---
  gcode::MachinePosition start() const override { return pos_; }
  void atLine(int line) override { line_ = line; }
  void rapid(const gcode::MachinePosition& to) override { move(requireFinite(to), false, 0); }
  void feed(const gcode::MachinePosition& to, double f) override { move(requireFinite(to), true, f); }
  gcode::ProbeOutcome probe(const gcode::MachinePosition& to, double, gcode::ProbeMode) override;
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
  void spindle(double rpm) override;
  void coolant(bool) override { event("coolant"); }
  void openLog(const std::string&) override { event("opening the log"); }
  void log(const std::string&) override { event("a log line (a point logged)"); }
  void closeLog() override { event("closing the log"); }

  void add(const std::string& rule, const std::string& what, const Vector3d& where, const std::string& limit);
  void addAt(int line, const std::string& rule, const std::string& what, const Vector3d& where, const std::string& limit);

  Vector3d tip(const gcode::MachinePosition& p) const { return p.xyz_mm - Vector3d(0, 0, toolOf(tool_).length); }

 private:
  const parts::Machine& m_;
  Options o_;
  std::map<int, Tool> tools_;
  Scene scene_;
  TiltAxis tilt_;
  double table_radius_ = 0;  // the table disc under a tilt (kTableRimMm)
  double reach_c_ = 0, reach_tilt_ = 0;  // farthest body point from the C axis / the tilting axis line
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
  const Tool& toolOf(int n) const;

  // --- the scene (safety_scene.cpp) ---
  void buildTools(const parts::TestPiece& piece);
  void buildScene(const parts::TestPiece& piece);
  void buildTiltReach();

  // --- geometry of a pose (safety_checker.cpp) ---
  Vector3d tableFrame(const Vector3d& p, double c_deg) const;
  // Distance of the tool at tip position t (table frame) to everything; at most cap for material.
  Hit distance(const Tool& tool, const Vector3d& t, Parts which, bool cutting, double cap) const;

  struct Motion {
    Vector3d a, b;  // tip, machine coordinates
    double c0 = 0, c1 = 0;
    double q0 = 0, q1 = 0;  // the tilting axis (A or B), deg
  };
  Vector3d at(const Motion& mo, double s) const {
    return tableFrame(mo.a + s * (mo.b - mo.a), mo.c0 + s * (mo.c1 - mo.c0));
  }
  double speed(const Motion& mo, const Tool& tool) const;
  double tiltOf(const gcode::MachinePosition& p) const { return tilt_.name == 'A' ? p.a_deg : tilt_.name == 'B' ? p.b_deg : 0.0; }
  Motion motionTo(const gcode::MachinePosition& to) const {
    return {tip(pos_), tip(to), pos_.c_deg, to.c_deg, tiltOf(pos_), tiltOf(to)};
  }

  struct Sweep {
    bool hit = false;
    double s_hit = 1;
    Hit h;
    double d_start = kInf, d_min = kInf;
    double s_min = 0;
  };
  // Conservative advancement: the distance bounds how far the tool may move unchecked. A hit
  // is a distance at or below `margin` (0: contact).
  Sweep sweep(const Tool& tool, const Motion& mo, Parts which, bool cutting, double cap, double min_step,
              double margin = 0) const;
  Hit poseDistance(const Tool& tool, const Motion& mo, double s, Parts which, bool cutting, double cap) const;

  void checkTravel(const gcode::MachinePosition& to);
  std::string moveName(bool feed) const { return feed ? "feed move (G1)" : "rapid move (G0)"; }
  void move(const gcode::MachinePosition& to, bool is_feed, double);
  void removeMaterial(const Tool& tool, const Motion& mo);
  gcode::ProbeOutcome probeNominal(const gcode::MachinePosition& to);

  // --- rotary moves (safety_rotary.cpp) ---
  // The circle every body on the table sweeps when C turns.
  double envelope() const;
  // A C move on the level table below the clearance plane (rule rotary-below-clearance).
  void checkTurn(const gcode::MachinePosition& to, const Tool& tool, const Motion& mo, bool tilt);
  // Is the table tilted (or tilting) anywhere in the motion, on a machine that locates the axis?
  bool tilted(const Motion& mo) const { return tilt_.located && (std::fabs(mo.q0) > 1e-9 || std::fabs(mo.q1) > 1e-9); }
  // A rotary move of the tilted or tilting table: the swept bodies and table against the tool
  // (rule tilt-swing).
  void checkSwing(const Tool& tool, const Motion& mo);
  // The tool at tip t (machine coordinates) against the bodies of the table at C c and tilt q.
  Hit tiltedDistance(const Tool& tool, const Vector3d& t, double c_deg, double q_deg, Parts which, bool cutting) const;
  // A machine point in the table frame at this pose, and back.
  Vector3d toTable(const Vector3d& p, double c_deg, double q_deg) const;
  Vector3d toMachine(const Vector3d& x, double c_deg, double q_deg) const;
  Eigen::Matrix3d tableRotation(double c_deg, double q_deg) const;  // table frame -> machine, directions
  Eigen::Matrix3d tiltRotation(double q_deg) const;
  Eigen::Matrix3d turnRotation(double c_deg) const;
  double tiltedTop(double c_deg, double q_deg) const;  // the highest body point at this pose
};

}  // namespace probeloop::verify::detail
