// A machine tool as a kinematic chain of rigid bodies (issue 33; ISO 230-1 error motions,
// seed 002 Sec. 2.3-2.4 and seed 003 eqs. 1-2 for the homogeneous transformation matrices).
//
// Two branches leave the machine frame (the bed, `b` of the ISO 10791-1 code): the
// workpiece branch (frame -> ... -> table -> workpiece) and the tool branch (frame -> ... ->
// spindle -> tool). Each body hangs on its parent by one joint, linear or rotary, with a
// nominal direction and, for a rotary joint, a point of its axis line, in the parent frame.
// On each body act two small error twists (translation mm, rotation rad):
// - `location`: the joint's location errors (ISO 230-1: position and orientation of the axis
//   line, zero position), constant, about the joint's reference point. On a linear joint it
//   acts before the motion, so its rotation tilts the direction of travel (squareness). On a
//   rotary joint it acts as Joint::location_convention says:
//   AxisLine (ISO 230-7, the default): the body turns about the displaced and tilted line;
//   the twist's part along the axis direction is the zero error; at q = 0 only the zero acts.
//   BodyOnAxis (seed 004's C table): the body is square to its axis and carries its error,
//   so the whole twist acts at every q, C's turn first (error x turn): the table tilts with
//   a tilted axis, as seed 004's model of the sphere centres has it;
// - `motion`: the component errors at the current position (positioning, straightness,
//   roll/pitch/yaw of a carriage; radial/axial/tilt motion of a spindle), applied after the
//   motion about the body's own origin. The caller evaluates them at the axis positions.
// Transformations are exact (not linearised): Trans(delta) Rot(x,ex) Rot(y,ey) Rot(z,ez)
// (seed 002 eqs. 3-7 without the small-angle step), so tests of first-order models see the
// true second-order terms.
//
// Sign conventions: rotations right-hand about +X, +Y, +Z (A, B, C); a rotary joint turns
// its body by +q about `direction`. An ISO 841 primed axis (workpiece side, C') is written
// with direction -Z (docs/kinematic-chains.md). Location-error names follow ISO 230-7:
// E<component>0<axis>, component X Y Z (um) or A B C (urad): EX0C, EA0B, EC0Z ...
#pragma once
#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

namespace probeloop::geometry {

struct Twist {
  Eigen::Vector3d translation_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation_rad = Eigen::Vector3d::Zero();  // about +X, +Y, +Z
  bool isZero() const { return translation_mm.isZero(0) && rotation_rad.isZero(0); }
};

// The exact transformation of an error twist: Trans(d) Rot(x,ex) Rot(y,ey) Rot(z,ez).
Eigen::Isometry3d twistTransform(const Twist& e);

struct Joint;
// A rotary joint's motion by q_deg with its location errors (the convention of the joint),
// in the parent frame; the simulator's tilting table uses it, so the truth and the
// evaluation's model cannot differ.
Eigen::Isometry3d rotaryJointTransform(const Joint& joint, double q_deg, const Twist& location);

enum class JointKind { Fixed, Linear, Rotary };

enum class LocationConvention { AxisLine, BodyOnAxis };

struct Joint {
  JointKind kind = JointKind::Fixed;
  std::string axis;                                        // "X", "B", "C", "Z1" ...
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();    // unit, parent frame
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();      // rotary: on the axis line; the
                                                           // location errors' reference point
  LocationConvention location_convention = LocationConvention::AxisLine;  // rotary joints
};

struct Body {
  std::string name;
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();  // body origin in the parent frame at q = 0
  Joint joint;
};

struct KinematicChain {
  std::vector<Body> workpiece_branch;  // from the frame outward to the workpiece
  std::vector<Body> tool_branch;       // from the frame outward to the tool
  Eigen::Vector3d tool_tip_mm = Eigen::Vector3d::Zero();  // in the last tool body's frame

  int bodyCount() const { return static_cast<int>(workpiece_branch.size() + tool_branch.size()); }
  // Index of a body over both branches (workpiece branch first); -1 when absent.
  int indexOfAxis(const std::string& axis) const;
  const Body& body(int index) const;
};

// Axis positions (mm for linear joints, deg for rotary) and the error twists per body, in
// KinematicChain::body() order; missing positions are 0, empty twist vectors mean no errors.
struct ChainState {
  std::map<std::string, double> positions;
  std::vector<Twist> location, motion;
  double position(const std::string& axis) const;
};

// Pose of the last body of each branch in the machine frame.
Eigen::Isometry3d workpieceFrame(const KinematicChain& chain, const ChainState& state);
Eigen::Isometry3d toolFrame(const KinematicChain& chain, const ChainState& state);

// Where a point fixed on the workpiece (workpiece-body frame) is in the machine frame.
Eigen::Vector3d workpiecePoint(const KinematicChain& chain, const ChainState& state, const Eigen::Vector3d& w_mm);
// The tool tip in the machine frame.
Eigen::Vector3d toolTip(const KinematicChain& chain, const ChainState& state);

// The axis positions of the three linear joints named X, Y, Z (mm, in that order) at which
// the tool tip meets the workpiece point w (workpiece-body frame), the other positions as
// in `state`: what a touch probe's machine coordinates report for that point. Newton on the
// exact chain; GeometryError if the chain lacks a linear X, Y or Z or does not converge.
Eigen::Vector3d machineCoordinatesOf(const KinematicChain& chain, const ChainState& state,
                                     const Eigen::Vector3d& w_mm);

// One scalar error parameter of the chain: a component of a body's location or motion twist.
struct ChainParameter {
  std::string name;    // ISO 230-7 symbol for location errors: "EX0C", "EB0B"; free otherwise
  int body = 0;        // KinematicChain::body() index
  bool location = true;
  int component = 0;   // 0-2 translation X Y Z (parameter in um), 3-5 rotation A B C (urad)
  double sign = 1.0;   // -1 for a parameter counted against the twist (seed 004's EC0C:
                       // positive = the table turned clockwise seen from +Z)
  // Adds `value` (um or urad) of this parameter to the state's twists (sized as needed).
  void addTo(ChainState& state, int body_count, double value) const;
};

// The location-error parameter of a body's joint for a component 0..5 (EX0C ... EC0C).
ChainParameter locationParameter(const KinematicChain& chain, const std::string& axis, int component);
// "EX0C" from the axis "C" and component 0; components: X Y Z A B C.
std::string locationErrorName(const std::string& axis, int component);

}  // namespace probeloop::geometry
