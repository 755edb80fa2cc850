#include "geometry/lathe_chain.hpp"

#include <cmath>
#include <stdexcept>

namespace probeloop::geometry {

using Eigen::Vector3d;

LatheOffsets latheDefaultOffsets() {
  LatheOffsets off;
  off.o[0] = Vector3d(320, 0, 700);  // Z carriage's home from machine zero
  off.o[1] = Vector3d(-40, 0, 15);   // X slide on the carriage
  off.o[2] = Vector3d(-30, 0, -60);  // turret centre on the slide
  off.o[3] = Vector3d(0, 0, 120);    // spindle nose on the spindle axis
  return off;
}

int latheChainIndex(int paper_body) {
  // workpiece branch first: [spindle (4)], then the tool branch [Z (1), X (2), turret (3)]
  if (paper_body == 4) return 0;
  if (paper_body >= 1 && paper_body <= 3) return paper_body;
  throw std::invalid_argument("lathe: bodies are numbered 1..4 (seed 002)");
}

KinematicChain latheChain(const LatheOffsets& off, const Vector3d& tool_tip_mm) {
  KinematicChain c;
  c.workpiece_branch.push_back(Body{"spindle (4)", off.o[3], {JointKind::Fixed, "", Vector3d::UnitZ(), Vector3d::Zero()}});
  c.tool_branch.push_back(Body{"Z carriage (1)", off.o[0], {JointKind::Linear, "Z", Vector3d::UnitZ(), Vector3d::Zero()}});
  c.tool_branch.push_back(Body{"X cross-slide (2)", off.o[1], {JointKind::Linear, "X", Vector3d::UnitX(), Vector3d::Zero()}});
  c.tool_branch.push_back(Body{"turret (3)", off.o[2], {JointKind::Fixed, "", Vector3d::UnitZ(), Vector3d::Zero()}});
  c.tool_tip_mm = tool_tip_mm;
  return c;
}

ChainState latheState(double x_mm, double z_mm, const LatheErrors& e) {
  ChainState s;
  s.positions = {{"X", x_mm}, {"Z", z_mm}};
  s.motion.resize(4);
  for (int b = 1; b <= 4; ++b) s.motion[static_cast<std::size_t>(latheChainIndex(b))] = e.body[static_cast<std::size_t>(b - 1)];
  return s;
}

Vector3d latheIdealToolOffset(const LatheOffsets& off, double x_mm, double z_mm, const Vector3d& w) {
  // seed 002 eq. 24: [-a1-a2-a3+a4-x+Wx, -b1-b2-b3+b4+Wy, -c1-c2-c3+c4-z+Wz] (-z: notes §2.4)
  return off.o[3] + w - off.o[0] - off.o[1] - off.o[2] - Vector3d(x_mm, 0, z_mm);
}

Eigen::Vector2d latheNominalXZ(const LatheOffsets& off, const Vector3d& t, const Vector3d& w) {
  const Vector3d d = off.o[3] + w - off.o[0] - off.o[1] - off.o[2] - t;
  return {d.x(), d.z()};
}

Vector3d latheVolumetricError(const KinematicChain& chain, double x_mm, double z_mm, const LatheErrors& e,
                              const Vector3d& w) {
  const ChainState s = latheState(x_mm, z_mm, e);
  return toolTip(chain, s) - workpiecePoint(chain, s, w);
}

Vector3d latheVolumetricErrorFirstOrder(const LatheOffsets& off, const Vector3d& t, double x_mm, double z_mm,
                                        const LatheErrors& e, const Vector3d& w) {
  // notes §2.5 (compact form), seed 002 eqs. 27-29 to first order
  std::array<Vector3d, 3> o;
  o[0] = off.o[0] + Vector3d(0, 0, z_mm);
  o[1] = o[0] + off.o[1] + Vector3d(x_mm, 0, 0);
  o[2] = o[1] + off.o[2];
  const Vector3d p_tip = o[2] + t;
  Vector3d p = Vector3d::Zero();
  for (std::size_t i = 0; i < 3; ++i)
    p += e.body[i].translation_mm + e.body[i].rotation_rad.cross(p_tip - o[i]);
  p -= e.body[3].translation_mm + e.body[3].rotation_rad.cross(w);
  return p;
}

LatheCutErrors latheCutErrors(const KinematicChain& chain, double x_mm, double z_mm, const LatheErrors& e,
                              const Vector3d& w) {
  const ChainState s = latheState(x_mm, z_mm, e);
  // the tip in the spindle frame: where the surface is cut, relative to the turning axis
  const Vector3d cut = workpieceFrame(chain, s).inverse() * toolTip(chain, s);
  LatheCutErrors r;
  r.diameter_mm = 2 * (std::hypot(cut.x(), cut.y()) - std::hypot(w.x(), w.y()));
  r.face_z_mm = cut.z() - w.z();
  return r;
}

std::vector<ChainParameter> latheParameters() {
  std::vector<ChainParameter> p;
  const char* comp[6] = {"dx", "dy", "dz", "ex", "ey", "ez"};
  for (int b = 1; b <= 4; ++b)
    for (int k = 0; k < 6; ++k)
      p.push_back(ChainParameter{std::string(comp[k]) + std::to_string(b), latheChainIndex(b), false, k});
  return p;
}

}  // namespace probeloop::geometry
