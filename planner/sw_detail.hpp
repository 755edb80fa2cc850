// Internal to the stepped-workpiece planner (stepped_workpiece.hpp is the public contract):
// what its files share. planSteppedWorkpiece builds one Builder, whose build() follows the
// steps a reader follows:
//   the experiment, its compensation and the inputs checked (stepped_workpiece.cpp) ->
//   roughing and finishing with the warm-ups (sw_machining.cpp, with the building blocks of
//   the programs) -> on-machine probing (sw_probing.cpp) -> the programs walked on the
//   machine's clock with the collision check against the material as each op finds it
//   (sw_collisions.cpp), the steps' times, the manifest and the CMM plan (sw_manifest.cpp).
// Nothing outside planner/ includes this header.
#pragma once
#include <Eigen/Dense>
#include <cmath>
#include <string>
#include <vector>

#include "parts/machine.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/stepped_workpiece.hpp"
#include "planner/piece_manifest.hpp"
#include "planner/program_walker.hpp"
#include "planner/stepped_workpiece.hpp"

namespace probeloop::planner::sw {

using Eigen::Vector2d;
using Eigen::Vector3d;
using parts::SteppedWorkpiece;

// "(x, y, z)" of a machine position, as the messages name it (sw_collisions.cpp).
std::string xyz(const Vector3d& v);

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
  std::vector<Box> boxes() const;
};

// Distance in XY from p to the rectangle |x| <= hx, |y| <= hy (0 inside; sw_collisions.cpp).
double rectDistance(const Vector2d& p, double hx, double hy);

class Builder {
 public:
  Builder(const SteppedWorkpiece& w, const std::string& experiment, const parts::Machine& m, parts::Dialect d,
          const parts::SwCompensation* comp);

  SteppedWorkpiecePlan build();

 private:
  // --- inputs the programs cannot be made of -------------------------------------------
  void checkInputs() const;

  // --- program building ----------------------------------------------------------------
  NotedProgram& P() { return programs_.back(); }
  void add(gcode::Op op, const std::string& where, bool cut = false, int cut_index = -1);
  void add(gcode::Op op, OpNote n);
  // Machine coordinates (rounded as written) of a point given relative to the steps' centre.
  double mx(double qx) const { return round4(O_.x() + c_ + qx); }
  double my(double qy) const { return round4(O_.y() + c_ + qy); }
  double mz(double z) const { return round4(O_.z() + z); }
  Vector3d mach(const Vector2d& q, double z) const { return {mx(q.x()), my(q.y()), mz(z)}; }

  void rapidXY(const Vector2d& q, const std::string& w);
  void rapidZ(double z, const std::string& w) { add(gcode::Rapid{std::nullopt, std::nullopt, mz(z)}, w); }
  void feedXY(const Vector2d& q, double F, const std::string& w, bool cut = false, int ci = -1);
  void feedZ(double z, double F, const std::string& w, bool cut = false);
  int addCut(const std::string& id, const std::string& feature, int step, const Vector2d& from, const Vector2d& to, double z);

  void newProgram(const std::string& role, const std::string& file, int number, const std::string& title);
  void toolChange(int tool, const std::string& w);
  void end(bool spindle);
  std::string toolLine() const;

  // One closed square contour of half size s about the centre, clockwise from its (-s, s)
  // corner (where the tool stands).
  void contour(double s, double F, const std::string& w, int ci, bool cut = true);

  // --- roughing (our choice: the thesis's preparation, L695-700) ----------------------------
  void roughing();

  // --- finishing: the experiment (Table 4.1, Sec. 4.1) ------------------------------------
  // The path of step k at its depth (floor contours, then the walls as the transition says);
  // `air` replays it at the clearance plane without cutting (the warm-up's axis manoeuvre).
  void stepPath(std::size_t k, bool air, const std::string& w);

  void finishing();

  // --- on-machine probing (Sec. 3.4, L1040) ------------------------------------------------
  struct Planned {
    Vector3d start, end, contact;
    int index;
  };
  Planned planPoint(const parts::SwProbePoint& p, int position, int point, bool cmm);

  void probing();

  // Whether a ball of radius rho moving from a to b (machine coordinates of its centre) keeps
  // clear of the material as it is now.
  bool pathClear(const Vector3d& a, const Vector3d& b, double rho) const;

  // --- walking: clock and checks ----------------------------------------------------------
  void check(const Motion& mo, const Material& mat) const;

  std::vector<WalkerTool> walkerTools() const;

  void walk();

  // --- manifest and CMM plan --------------------------------------------------------------
  void manifest();

  std::string cmmCsv() const;

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

}  // namespace probeloop::planner::sw
