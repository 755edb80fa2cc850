#include "model/structural_stiffness.hpp"

#include <Eigen/Geometry>
#include <string>

#include "core/error.hpp"

namespace probeloop::model {

double shearTranslation_mm(double F_N, double k_N_per_mm) { return F_N / (4.0 * k_N_per_mm); }  // seed 003 eq. 28

double momentRotation_rad(double F_N, double R_mm, double k_N_per_mm, double S_mm) {
  // seed 003 eq. 29: each support of the couple carries F R / (2 S) (eq. 16), yields by that
  // over k, and the unit turns by that yield over the half spacing S / 2.
  return F_N * R_mm / (k_N_per_mm * S_mm * S_mm);
}

double leverDisplacement_mm(double angle_rad, double arm_mm) { return angle_rad * arm_mm; }  // seed 003 eq. 63

Twist unitTwist(const StructuralUnit& u, const Eigen::Vector3d& F_N) {
  Twist t;
  for (int f = 0; f < 3; ++f)
    if (u.shear[f] && F_N(f) != 0) {
      if (!(u.k_N_per_mm(f) > 0)) throw InputError("", 0, u.name + ": a shear direction needs a stiffness > 0");
      t.delta_mm(f) = shearTranslation_mm(F_N(f), u.k_N_per_mm(f));
    }
  for (const auto& p : u.moments) {
    const double F = F_N(p.force_axis);
    if (F == 0) continue;
    if (!(u.k_N_per_mm(p.force_axis) > 0 && p.S_mm > 0))
      throw InputError("", 0, u.name + ": a moment path needs a stiffness > 0 and a support spacing > 0");
    // The rotation follows the moment (R lever) x (F e_f); its size is eq. 29's F R / (k S^2).
    const Eigen::Vector3d axis = p.lever.cross(Eigen::Vector3d::Unit(p.force_axis));
    if (axis.norm() < 0.5) throw InputError("", 0, u.name + ": a moment path's lever must be perpendicular to its force");
    t.eps_rad += axis * momentRotation_rad(F, p.R_mm, u.k_N_per_mm(p.force_axis), p.S_mm);
  }
  return t;
}

Eigen::Vector3d tcpDisplacement_mm(const Twist& t, const Eigen::Vector3d& arm_mm) {
  return t.delta_mm + t.eps_rad.cross(arm_mm);  // first order (notes §5; seed 003 eqs. 11-13)
}

Eigen::Vector3d tcpDisplacement_mm(const std::vector<StructuralUnit>& units, const Eigen::Vector3d& F_N) {
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  for (const auto& u : units) d += tcpDisplacement_mm(unitTwist(u, F_N), u.arm_mm);
  return d;
}

std::vector<StructuralUnit> seed003Gantry(const Seed003Stiffness& k, const Seed003Geometry& g) {
  using V = Eigen::Vector3d;
  StructuralUnit cb;
  cb.name = "crossbeam";
  cb.k_N_per_mm = V(k.k_cbx, k.k_cby, k.k_cbz);
  cb.shear = {true, true, false};  // eqs. 30, 28; a Z force runs along the head's travel (eq. 23)
  // Lever directions from the printed signs: eq. 62 +, eq. 66 +, eq. 69 +, eq. 72 -.
  cb.moments = {{1, V::UnitX(), g.R_cby, g.D_cb, "seed 003 eq. 29"},
                {0, -V::UnitY(), g.R_cbx, g.D_cb, "seed 003 eq. 31"},
                {2, V::UnitY(), g.R_cbz2, g.L_cb, "seed 003 eq. 33"},
                {2, V::UnitX(), g.R_cbz1, g.L_cb, "seed 003 eq. 35"}};
  // gamma: X = gamma x 40 (eqs. 64, 68), Y = gamma x 75 (eqs. 63, 67); alpha: Y = alpha x 40 (eq. 71).
  cb.arm_mm = V(75, -40, -40);
  StructuralUnit mb;
  mb.name = "machine bed";
  mb.k_N_per_mm = V(k.k_mbx, k.k_mby, k.k_mbz);
  mb.shear = {false, true, true};  // eqs. 50, 52; the beam slides in X (L526)
  // Printed signs: eq. 73 -, eq. 77 -, eq. 79 +, eq. 80 +.
  mb.moments = {{0, V::UnitY(), g.R_mbx, g.L_mb, "seed 003 eq. 49"},
                {1, -V::UnitX(), g.R_mby, g.L_mb, "seed 003 eq. 51"},
                {2, V::UnitY(), g.R_mb, g.D_mb, "seed 003 eq. 53"},
                {2, -V::UnitX(), g.R_mby, g.D_mb, "seed 003 eq. 54"}};
  // gamma_mbx: X = |gamma| x 20 (eq. 75), Y = |gamma| x 75 (eq. 74, the correct value).
  mb.arm_mm = V(-75, 20, 0);
  return {cb, mb};
}

}  // namespace probeloop::model
