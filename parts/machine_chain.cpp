#include "parts/machine_chain.hpp"

#include "core/error.hpp"

namespace probeloop::parts {

using Eigen::Vector3d;
using geometry::Body;
using geometry::JointKind;

std::string tiltAxisName(const Machine& m) { return m.b.present ? "B" : m.a.present ? "A" : ""; }

geometry::KinematicChain machineChain(const Machine& m, std::optional<double> c_reference_z_mm, bool need_tilt) {
  geometry::KinematicChain chain;
  const char* names[3] = {"X", "Y", "Z"};
  for (int k = 0; k < 3; ++k) {
    Body b;
    b.name = std::string(names[k]) + " slide";
    b.joint.kind = JointKind::Linear;
    b.joint.axis = names[k];
    b.joint.direction = Vector3d::Unit(k) * (m.workpiece_side[static_cast<std::size_t>(k)] ? -1.0 : 1.0);
    (m.workpiece_side[static_cast<std::size_t>(k)] ? chain.workpiece_branch : chain.tool_branch).push_back(b);
  }
  const std::string tilt = tiltAxisName(m);
  if (!tilt.empty()) {
    const auto& centre = tilt == "B" ? m.b_axis_centre_xz_mm : m.a_axis_centre_yz_mm;
    if (centre) {
      const RotaryAxis& ax = tilt == "B" ? m.b : m.a;
      Body b;
      b.name = tilt == "B" ? "B trunnion" : "A cradle";
      b.joint.kind = JointKind::Rotary;
      b.joint.axis = tilt;
      const int k = tilt == "B" ? 1 : 0;
      b.joint.direction = Vector3d::Unit(k) * (ax.positive_is_clockwise ? -1.0 : 1.0);
      b.joint.point_mm = tilt == "B" ? Vector3d(centre->x(), 0, centre->y()) : Vector3d(0, centre->x(), centre->y());
      chain.workpiece_branch.push_back(b);
    } else if (need_tilt) {
      throw InputError(m.file, 0, std::string(tilt == "B" ? "b_axis" : "a_axis") +
                                      ": the cycle tilts the table, so the machine must say where the " + tilt +
                                      " axis lies (" + (tilt == "B" ? "centre_x, centre_z" : "centre_y, centre_z") +
                                      ", machine coordinates of the tip at " + tilt + " = 0)");
    }
  }
  if (m.c.present) {
    Body c;
    c.name = "C table";
    c.joint.kind = JointKind::Rotary;
    c.joint.axis = "C";
    // The table is square to its axis and carries its error (seed 004's model: EA0C tilts the
    // table and the sphere on it); the tilting axis is a line (ISO 230-7, the default).
    c.joint.location_convention = geometry::LocationConvention::BodyOnAxis;
    c.joint.direction = Vector3d::UnitZ() * (m.c.positive_is_clockwise ? -1.0 : 1.0);
    c.joint.point_mm = Vector3d(m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y(),
                                c_reference_z_mm.value_or(m.table_surface_z_mm));
    chain.workpiece_branch.push_back(c);
  }
  return chain;
}

}  // namespace probeloop::parts
