#include "geometry/kinematic_chain.hpp"

#include <cmath>
#include <stdexcept>

#include "core/error.hpp"

namespace probeloop::geometry {

using Eigen::AngleAxisd;
using Eigen::Isometry3d;
using Eigen::Vector3d;

namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

Isometry3d translation(const Vector3d& v) {
  Isometry3d t = Isometry3d::Identity();
  t.translation() = v;
  return t;
}

Isometry3d turn(const Vector3d& direction, double rad) {
  Isometry3d r = Isometry3d::Identity();
  r.linear() = AngleAxisd(rad, direction).toRotationMatrix();
  return r;
}

// Parent -> body at the state's position, with the body's error twists.
Isometry3d bodyTransform(const Body& b, const ChainState& s, int index) {
  const Vector3d& p = b.joint.point_mm;
  Isometry3d t = translation(b.origin_mm);
  const bool located = index < static_cast<int>(s.location.size()) && !s.location[index].isZero();
  const double q = b.joint.kind == JointKind::Fixed ? 0.0 : s.position(b.joint.axis);
  if (b.joint.kind == JointKind::Rotary) {
    t = t * rotaryJointTransform(b.joint, q, located ? s.location[index] : Twist{});
  } else {
    if (located) t = t * translation(p) * twistTransform(s.location[index]) * translation(-p);
    if (b.joint.kind == JointKind::Linear) t = t * translation(q * b.joint.direction);
  }
  if (index < static_cast<int>(s.motion.size()) && !s.motion[index].isZero()) t = t * twistTransform(s.motion[index]);
  return t;
}

Isometry3d branch(const std::vector<Body>& bodies, const ChainState& s, int first_index) {
  Isometry3d t = Isometry3d::Identity();
  for (std::size_t i = 0; i < bodies.size(); ++i) t = t * bodyTransform(bodies[i], s, first_index + static_cast<int>(i));
  return t;
}

}  // namespace

Isometry3d rotaryJointTransform(const Joint& j, double q_deg, const Twist& e) {
  const Vector3d& p = j.point_mm;
  const Vector3d& d = j.direction;
  if (e.isZero()) return q_deg == 0 ? Isometry3d::Identity() : translation(p) * turn(d, q_deg * kDegToRad) * translation(-p);
  if (j.location_convention == LocationConvention::BodyOnAxis)
    return translation(p) * twistTransform(e) * turn(d, q_deg * kDegToRad) * translation(-p);
  // The line: displaced and tilted across the axis (what lies along it is no error of a line);
  // the zero: a turn about it.
  Twist line;
  line.translation_mm = e.translation_mm - e.translation_mm.dot(d) * d;
  line.rotation_rad = e.rotation_rad - e.rotation_rad.dot(d) * d;
  const Isometry3d L = twistTransform(line);
  return translation(p) * L * turn(d, q_deg * kDegToRad + e.rotation_rad.dot(d)) * L.inverse() * translation(-p);
}

Isometry3d twistTransform(const Twist& e) {
  Isometry3d t = Isometry3d::Identity();
  t.linear() = (AngleAxisd(e.rotation_rad.x(), Vector3d::UnitX()) * AngleAxisd(e.rotation_rad.y(), Vector3d::UnitY()) *
                AngleAxisd(e.rotation_rad.z(), Vector3d::UnitZ()))
                   .toRotationMatrix();
  t.translation() = e.translation_mm;
  return t;
}

int KinematicChain::indexOfAxis(const std::string& axis) const {
  for (int i = 0; i < bodyCount(); ++i)
    if (body(i).joint.kind != JointKind::Fixed && body(i).joint.axis == axis) return i;
  return -1;
}

const Body& KinematicChain::body(int index) const {
  const int n = static_cast<int>(workpiece_branch.size());
  return index < n ? workpiece_branch.at(index) : tool_branch.at(index - n);
}

double ChainState::position(const std::string& axis) const {
  const auto it = positions.find(axis);
  return it == positions.end() ? 0.0 : it->second;
}

Isometry3d workpieceFrame(const KinematicChain& c, const ChainState& s) { return branch(c.workpiece_branch, s, 0); }

Isometry3d toolFrame(const KinematicChain& c, const ChainState& s) {
  return branch(c.tool_branch, s, static_cast<int>(c.workpiece_branch.size()));
}

Vector3d workpiecePoint(const KinematicChain& c, const ChainState& s, const Vector3d& w) { return workpieceFrame(c, s) * w; }

Vector3d toolTip(const KinematicChain& c, const ChainState& s) { return toolFrame(c, s) * c.tool_tip_mm; }

Vector3d machineCoordinatesOf(const KinematicChain& c, const ChainState& state, const Vector3d& w) {
  const char* names[3] = {"X", "Y", "Z"};
  for (const char* n : names) {
    const int i = c.indexOfAxis(n);
    if (i < 0 || c.body(i).joint.kind != JointKind::Linear)
      throw GeometryError(std::string("kinematic chain: no linear axis ") + n + " to reach a workpiece point with");
  }
  ChainState s = state;
  auto gap = [&](const ChainState& st) { return Vector3d(toolTip(c, st) - workpiecePoint(c, st, w)); };
  // The gap is affine in the linear positions up to the errors' second order: a few Newton
  // steps with a finite-difference Jacobian (steps of 1 mm, exact for an affine map) converge.
  for (int iter = 0; iter < 8; ++iter) {
    const Vector3d g = gap(s);
    Eigen::Matrix3d J;
    for (int k = 0; k < 3; ++k) {
      ChainState t = s;
      t.positions[names[k]] += 1.0;
      J.col(k) = gap(t) - g;
    }
    Eigen::FullPivLU<Eigen::Matrix3d> lu(J);
    if (!lu.isInvertible())
      throw GeometryError("kinematic chain: the linear axes X, Y, Z do not span space at this position");
    const Vector3d step = lu.solve(-g);
    for (int k = 0; k < 3; ++k) s.positions[names[k]] += step(k);
    if (step.norm() < 1e-12) break;
  }
  if (gap(s).norm() > 1e-9) throw GeometryError("kinematic chain: no axis position brings the tool to the point");
  return Vector3d(s.position("X"), s.position("Y"), s.position("Z"));
}

void ChainParameter::addTo(ChainState& s, int body_count, double value) const {
  auto& v = location ? s.location : s.motion;
  if (static_cast<int>(v.size()) < body_count) v.resize(body_count);
  if (component < 3) v.at(body).translation_mm(component) += sign * value * 1e-3;
  else v.at(body).rotation_rad(component - 3) += sign * value * 1e-6;
}

std::string locationErrorName(const std::string& axis, int component) {
  static const char* comp[6] = {"X", "Y", "Z", "A", "B", "C"};
  return std::string("E") + comp[component] + "0" + axis;
}

ChainParameter locationParameter(const KinematicChain& c, const std::string& axis, int component) {
  const int i = c.indexOfAxis(axis);
  if (i < 0) throw std::invalid_argument("kinematic chain: no axis " + axis);
  if (component < 0 || component > 5) throw std::invalid_argument("location error component out of 0..5");
  return ChainParameter{locationErrorName(axis, component), i, true, component};
}

}  // namespace probeloop::geometry
