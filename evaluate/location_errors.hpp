// Location errors of the C axis from sphere centres, relative to a reference cycle
// (seed 004 §5.2: cycle 1 is the reference, geometric errors cancel).
//
// Two estimators, both linear in the centre coordinates:
// - gebhardtFormulas: seed 004 Eqs. 5.4-5.10 exactly as printed, for the four positions
//   whose manifest formula_index is 1..4 (-X, +Y, +X, -Y of the axis).
// - LocationLeastSquares: for any N >= 3 positions at any angles: the first-order
//   rigid-body model of a circle of sphere centres in a tilted plane,
//     dx_k = EX + ER cos(t_k) - c R sin(t_k)
//     dy_k = EY + ER sin(t_k) + c R cos(t_k)        (c = -EC0C, R = d/2)
//     dz_k = EZ + R (EA sin(t_k) - EB cos(t_k)),
//   solved by least squares. With the four thesis positions its normal equations are
//   diagonal and it reproduces Eqs. 5.4-5.10 exactly (docs/location-errors.md derives it).
#pragma once
#include <Eigen/Dense>
#include <vector>

#include "geometry/location_errors.hpp"

namespace probeloop::evaluate {

using geometry::LocationErrors;

// centres[k] for formula index k+1 of cycle i and of the reference cycle; d_m = 2 * d/2 in m.
LocationErrors gebhardtFormulas(const std::array<Eigen::Vector3d, 4>& cycle_mm,
                                const std::array<Eigen::Vector3d, 4>& reference_mm, double d_m);

class LocationLeastSquares {
 public:
  // angles_deg: nominal angle of each used position about the C axis (machine frame);
  // radius_mm: d/2. GeometryError if the angles do not separate all seven errors.
  LocationLeastSquares(const std::vector<double>& angles_deg, double radius_mm);

  // Centres of the used positions (same order as the angles), cycle and reference.
  LocationErrors solve(const std::vector<Eigen::Vector3d>& cycle_mm,
                       const std::vector<Eigen::Vector3d>& reference_mm) const;

  // d(error_j)/d(coordinate) in (um or urad)/mm: 7 x 3N, coordinates ordered x1,y1,z1,x2...
  // The same matrix applies to the cycle's centres and, negated, to the reference's.
  const Eigen::MatrixXd& sensitivity() const { return W_; }
  // The first-order model: centre displacements (mm) = design() * errors (3N x 7).
  const Eigen::MatrixXd& design() const { return A_; }

  // Residual standard deviation of the model fit to one cycle's displacements (um), and its
  // degrees of freedom (2N-4 in XY, N-3 in Z): a type A check of the rigid-body model.
  struct Residual { double xy_um = 0, z_um = 0; int dof_xy = 0, dof_z = 0; };
  Residual residual(const std::vector<Eigen::Vector3d>& cycle_mm,
                    const std::vector<Eigen::Vector3d>& reference_mm) const;

 private:
  Eigen::MatrixXd A_;  // 3N x 7 design (rows x1,y1,z1,...; columns in LocationErrors order)
  Eigen::MatrixXd W_;  // 7 x 3N
};

}  // namespace probeloop::evaluate
