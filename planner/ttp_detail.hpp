// Internal to the thermal-test-piece planner (thermal_test_piece.hpp is the public contract):
// what its files share. planThermalTestPiece builds one Builder, whose build() follows the
// steps a reader follows:
//   the layout checked (thermal_test_piece.cpp) -> pre-machining and the test with its C load
//   (ttp_machining.cpp) -> the on-machine inspection (ttp_inspection.cpp) -> the programs
//   walked on the machine's clock with the collision rules, the manifest and the CMM plan
//   (ttp_manifest.cpp).
// Each step writes its programs through the building blocks of ttp_program.cpp (ops with their
// notes, moves in part coordinates, tool changes, travel round the part, zig-zag passes); the
// collision rules of docs/thermal-test-piece.md §5 and the part's 2D geometry are in
// ttp_collisions.cpp. Nothing outside planner/ includes this header.
#pragma once
#include <Eigen/Dense>
#include <array>
#include <initializer_list>
#include <string>
#include <vector>

#include "parts/machine.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/thermal_test_piece.hpp"
#include "planner/piece_manifest.hpp"
#include "planner/program_walker.hpp"
#include "planner/thermal_test_piece.hpp"

namespace probeloop::planner::ttp {

using Eigen::Vector2d;
using Eigen::Vector3d;
using parts::FacetSide;
using parts::ThermalTestPiece;


// A tool's edge keeps this far outside the blank where passes start and end, and on the chords
// of the ring (our choice: the description states only the ring).
inline constexpr double kOutside = 2.0;
// The longest step along the ring, so that it looks like one and stays well outside.
inline constexpr double kMaxRingStepDeg = 30.0;
// The most whole turns one C feed move of the load may command (8-digit C words).
inline constexpr int kMaxTurnsPerMove = 277;
// Z-path inspection points keep this far from the strips the test's facet cuts sweep over the
// notch floor (as the loader keeps facet points from a facet's edge; docs §5).
inline constexpr double kStripMargin = 0.5;

// --- 2D geometry of the finished part (ttp_collisions.cpp) -------------------------------

using Poly = std::vector<Vector2d>;

// Distance from p to the segment a-b.
double pointSegment(const Vector2d& p, const Vector2d& a, const Vector2d& b);
// Distance from the C axis (the origin) to the segment a-b.
double segmentOrigin(const Vector2d& a, const Vector2d& b);


// What stands on the table, in the part frame: the blank's cylinder (pre-machining, and below
// the notch floor afterwards), above the floor the four segments with their facets at the
// pre-machining allowance (a superset of the part at any later time), the fixture below.
struct Envelope {
  double R = 0, H = 0, blank_top = 0, floor = 0, fixture_r = 0;
  std::vector<Poly> segments;
  double segments_r = 0;  // farthest point of a segment from the axis

  explicit Envelope(const ThermalTestPiece& t);
  double top(bool finished) const { return finished ? 0.0 : blank_top; }
};

// "X.. Y.. Z.." of a machine position, as the messages name it.
std::string xyz(const Vector3d& v);

// The collision rules of docs/thermal-test-piece.md §5 for every motion the walker is about to
// make (SafetyError "<program>: <where>: ..."). `finished`: after pre-machining, when the
// notches and the facets (at their allowance) have opened the part.
struct Collisions {
  const Envelope& env;
  Vector3d O;  // part origin, machine tip coordinates at C = 0
  bool cw;     // +C turns the table clockwise (C')

  void check(const Motion& mo, bool finished) const;
};

// The walker's tools: the piece's cutters (ttp_manifest.cpp).
std::vector<WalkerTool> walkerTools(const ThermalTestPiece& t);

// --- passes (ttp_program.cpp) -----------------------------------------------------------

// Evenly spaced lanes over [-half, half] no farther apart than `step`.
std::vector<double> lanes(double half, double step);

// Levels from 0 down to -depth in steps no deeper than `step`.
std::vector<double> levels(double depth, double step);

class Builder {
 public:
  Builder(const ThermalTestPiece& t, const std::vector<parts::NominalFeature>& features,
          const std::vector<parts::EvaluationRule>& evaluation, const parts::Machine& m, parts::Dialect d);

  ThermalTestPiecePlan build();

 private:
  // --- the layout ---------------------------------------------------------------------------
  const parts::NominalFeature& feature(const std::string& id) const;

  // The description's layout must leave every surface the programs cut and probe: an
  // InputError naming the key, never a NaN in a program (docs/thermal-test-piece.md §5).
  void checkLayout() const;

  // The TOP points of the +X+Y segment (mirrored into the others): two on the circle a - 2 r_tip
  // at 30 % and 70 % of the segment's angle between the notches (2 r_tip clear of both), one
  // 2 r_tip outside the notch corner on the middle angle. InputError when the notches leave no
  // room for them.
  std::array<Vector2d, 3> topPoints() const;

  // --- program building ----------------------------------------------------------------
  NotedProgram& P() { return programs_.back(); }
  void add(gcode::Op op, const std::string& where, bool cut = false, int cut_index = -1);
  void add(gcode::Op op, OpNote n);
  double radius(int tool) const { return t_.tool(tool)->diameter_mm / 2; }
  // Machine coordinates (rounded as written) of a point given relative to the C axis at the
  // height of the part origin: q = machine - origin.
  double mx(double qx) const { return round4(O_.x() + qx); }
  double my(double qy) const { return round4(O_.y() + qy); }
  double mz(double z) const { return round4(O_.z() + z); }
  Vector3d mach(double qx, double qy, double z) const { return {mx(qx), my(qy), mz(z)}; }

  void rapidXY(double qx, double qy, const std::string& w);
  void rapidZ(double z, const std::string& w);
  void feedXY(double qx, double qy, double F, const std::string& w, bool cut = false, int ci = -1);
  void feedZ(double z, double F, const std::string& w, bool cut = false);
  void indexC(double c, const std::string& w);
  void checkCResolution(double c, const std::string& w) const;
  void toolChange(int tool, const std::string& w);
  void spindleOn(double rpm, bool coolant, const std::string& w);
  void spindleOff(bool coolant, const std::string& w);
  // Pre-machining's change to the next step's cutter: nothing when it is in the spindle already,
  // else spindle (and coolant) off, retract, change, spindle on.
  void cutterFor(int tool, const std::string& w);
  int addCut(const std::string& id, const std::string& feature, int cycle, int tool, double c, const Vector3d& from,
             const Vector3d& to);

  void newProgram(const std::string& role, const std::string& file, int number, const std::string& title);
  void toolHeader(std::initializer_list<int> tools);

  // Moves at the current Z below the top of the part go around it: straight when the line
  // keeps the tool `kOutside` outside the blank, else radially out to the ring, along it in
  // chords that stay outside, and radially in (docs/thermal-test-piece.md §5).
  void travel(const Vector2d& to, int tool, const std::string& w);

  // Zig-zag passes across the blank from outside to outside: along Y (lanes in x) or X.
  void passes(bool along_y, const std::vector<double>& lane_list, const std::vector<double>& level_list, int tool, double F,
              const std::string& w);

  // --- pre-machining (seed 004 L2002-L2018) ----------------------------------------------
  void preMachining();

  // --- the test (L2022-L2047, docs/thermal-test-piece.md §2) ---------------------------
  void test();

  // The wait before cycle `cy`: the load of its phase (warm-up: C turning; hold: NC hold at C 0).
  void load(const parts::TtpCuttingCycle& cy);

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
  Planned planPoint(const std::string& feature, int position, int point, const ProbePoint& p);
  // Protected move to the start (unless the probe stands there already), measuring move,
  // back to the start.
  void probe(const Planned& p, int position, int point, const std::string& w, bool at_start = false);

  void inspection();

  // --- walking: clock and checks ----------------------------------------------------------
  void walk();
  // --- manifest and CMM plan --------------------------------------------------------------
  void manifest();

  std::string cmmCsv() const;

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

}  // namespace probeloop::planner::ttp
