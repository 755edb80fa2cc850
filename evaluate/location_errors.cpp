#include "evaluate/location_errors.hpp"

#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "core/units.hpp"

namespace probeloop::evaluate {

LocationErrors gebhardtFormulas(const std::array<Eigen::Vector3d, 4>& p,
                                const std::array<Eigen::Vector3d, 4>& p1, double d_m) {
  // Written as printed, with k = 1..4 -> index 0..3, i = this cycle, 1 = reference.
  auto x = [](const std::array<Eigen::Vector3d, 4>& c, int k) { return c[k - 1].x() * 1e3; };
  auto y = [](const std::array<Eigen::Vector3d, 4>& c, int k) { return c[k - 1].y() * 1e3; };
  auto z = [](const std::array<Eigen::Vector3d, 4>& c, int k) { return c[k - 1].z() * 1e3; };
  const double d = d_m;  // coordinates in um, d in m -> angles in um/m
  LocationErrors e;
  e.EX0C_um = 0.25 * (x(p, 1) + x(p, 2) + x(p, 3) + x(p, 4)) -
              0.25 * (x(p1, 1) + x(p1, 2) + x(p1, 3) + x(p1, 4));  // seed 004 Eq. 5.4
  e.EY0C_um = 0.25 * (y(p, 1) + y(p, 2) + y(p, 3) + y(p, 4)) -
              0.25 * (y(p1, 1) + y(p1, 2) + y(p1, 3) + y(p1, 4));  // seed 004 Eq. 5.5
  e.EZ0T_um = 0.25 * (z(p, 1) + z(p, 2) + z(p, 3) + z(p, 4)) -
              0.25 * (z(p1, 1) + z(p1, 2) + z(p1, 3) + z(p1, 4));  // seed 004 Eq. 5.6
  e.ER0T_um = 0.25 * (x(p, 3) + y(p, 2) - x(p, 1) - y(p, 4)) -
              0.25 * (x(p1, 3) + y(p1, 2) - x(p1, 1) - y(p1, 4));  // seed 004 Eq. 5.7
  e.EA0C_urad = (1 / d) * (z(p, 2) - z(p, 4)) - (1 / d) * (z(p1, 2) - z(p1, 4));  // Eq. 5.8
  e.EB0C_urad = (1 / d) * (z(p, 1) - z(p, 3)) - (1 / d) * (z(p1, 1) - z(p1, 3));  // Eq. 5.9
  e.EC0C_urad = (1 / (2 * d)) * (y(p, 1) + x(p, 2) - y(p, 3) - x(p, 4)) -
                (1 / (2 * d)) * (y(p1, 1) + x(p1, 2) - y(p1, 3) - x(p1, 4));  // Eq. 5.10
  return e;
}

LocationLeastSquares::LocationLeastSquares(const std::vector<double>& angles_deg, double R) {
  const int n = static_cast<int>(angles_deg.size());
  if (n < 3)
    throw GeometryError("location errors need >= 3 C positions; got " + std::to_string(n));
  A_ = Eigen::MatrixXd::Zero(3 * n, 7);
  for (int k = 0; k < n; ++k) {
    const double t = degToRad(angles_deg[k]);
    const double c = std::cos(t), s = std::sin(t);
    // Columns: EX um, EY um, EZ um, ER um, EA urad, EB urad, EC urad; rows in mm.
    A_.row(3 * k) << 1e-3, 0, 0, 1e-3 * c, 0, 0, R * 1e-6 * s;        // -c R sin, c = -EC
    A_.row(3 * k + 1) << 0, 1e-3, 0, 1e-3 * s, 0, 0, -R * 1e-6 * c;   // +c R cos
    A_.row(3 * k + 2) << 0, 0, 1e-3, 0, R * 1e-6 * s, -R * 1e-6 * c, 0;
  }
  // Identifiability: singular values of the column-scaled design.
  Eigen::MatrixXd scaled = A_;
  for (int j = 0; j < 7; ++j) scaled.col(j).normalize();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  if (sv(6) < 1e-8 * sv(0)) {
    std::ostringstream m;
    m << "the " << n << " C positions (angles";
    for (double a : angles_deg) m << " " << a;
    m << " deg about the axis) do not separate all seven location errors: EZ0T, EA0C and EB0C "
         "need >= 3 distinct angles not all on one line through the axis; spread the positions "
         "over the turn (e.g. 0/90/180/270)";
    throw GeometryError(m.str());
  }
  W_ = A_.completeOrthogonalDecomposition().pseudoInverse();
}

namespace {
Eigen::VectorXd deltas(const std::vector<Eigen::Vector3d>& c, const std::vector<Eigen::Vector3d>& r) {
  Eigen::VectorXd d(3 * c.size());
  for (size_t k = 0; k < c.size(); ++k) d.segment<3>(3 * k) = c[k] - r[k];
  return d;
}
}  // namespace

LocationErrors LocationLeastSquares::solve(const std::vector<Eigen::Vector3d>& c,
                                           const std::vector<Eigen::Vector3d>& r) const {
  if (static_cast<Eigen::Index>(3 * c.size()) != W_.cols() || c.size() != r.size())
    throw GeometryError("location least squares: number of centres does not match the positions");
  const Eigen::VectorXd e = W_ * deltas(c, r);
  std::array<double, 7> v;
  for (int j = 0; j < 7; ++j) v[j] = e(j);
  return LocationErrors::fromValues(v);
}

LocationLeastSquares::Residual LocationLeastSquares::residual(
    const std::vector<Eigen::Vector3d>& c, const std::vector<Eigen::Vector3d>& r) const {
  const Eigen::VectorXd d = deltas(c, r);
  const Eigen::VectorXd res = d - A_ * (W_ * d);
  const int n = static_cast<int>(c.size());
  Residual out;
  out.dof_xy = 2 * n - 4;
  out.dof_z = n - 3;
  double sxy = 0, sz = 0;
  for (int k = 0; k < n; ++k) {
    sxy += res(3 * k) * res(3 * k) + res(3 * k + 1) * res(3 * k + 1);
    sz += res(3 * k + 2) * res(3 * k + 2);
  }
  out.xy_um = out.dof_xy > 0 ? std::sqrt(sxy / out.dof_xy) * 1e3 : 0.0;
  out.z_um = out.dof_z > 0 ? std::sqrt(sz / out.dof_z) * 1e3 : 0.0;
  return out;
}

}  // namespace probeloop::evaluate
