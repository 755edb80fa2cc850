#include "geometry/identifiability.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace probeloop::geometry {

Eigen::MatrixXd chainSensitivity(const std::function<Eigen::VectorXd(const ChainState&)>& observe,
                                 const ChainState& base, const std::vector<ChainParameter>& params,
                                 int body_count) {
  Eigen::MatrixXd J;
  for (std::size_t j = 0; j < params.size(); ++j) {
    ChainState plus = base, minus = base;
    params[j].addTo(plus, body_count, 1.0);
    params[j].addTo(minus, body_count, -1.0);
    const Eigen::VectorXd d = (observe(plus) - observe(minus)) / 2.0;
    if (j == 0) J.resize(d.size(), static_cast<Eigen::Index>(params.size()));
    J.col(static_cast<Eigen::Index>(j)) = d;
  }
  return J;
}

Identifiability identifiability(const Eigen::MatrixXd& J, const std::vector<std::string>& names, double tol) {
  const Eigen::Index p = J.cols();
  if (static_cast<Eigen::Index>(names.size()) != p) throw std::invalid_argument("identifiability: one name per column");
  Identifiability out;
  out.names = names;
  out.identifiable.assign(static_cast<std::size_t>(p), true);
  if (p == 0) return out;
  Eigen::VectorXd scale(p);
  for (Eigen::Index j = 0; j < p; ++j) scale(j) = J.col(j).norm();
  const double top = scale.maxCoeff();
  Eigen::MatrixXd Jn = J;
  for (Eigen::Index j = 0; j < p; ++j) Jn.col(j) = scale(j) > tol * top ? Eigen::VectorXd(J.col(j) / scale(j)) : Eigen::VectorXd::Zero(J.rows());
  // Null space from the eigenvectors of Jn^T Jn: p is small (tens), the rows many.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Jn.transpose() * Jn);
  const Eigen::VectorXd& ev = es.eigenvalues();  // ascending
  const double limit = std::max(ev(p - 1), 1.0) * tol;
  std::vector<Eigen::VectorXd> basis;
  for (Eigen::Index k = 0; k < p; ++k)
    if (ev(k) <= limit) basis.push_back(es.eigenvectors().col(k));
  out.rank = static_cast<int>(p) - static_cast<int>(basis.size());
  if (basis.empty()) return out;
  // Back to the parameters' own units, then reduced row echelon form of the relations.
  Eigen::MatrixXd N(basis.size(), p);
  for (std::size_t r = 0; r < basis.size(); ++r)
    for (Eigen::Index j = 0; j < p; ++j)
      N(static_cast<Eigen::Index>(r), j) = scale(j) > tol * top ? basis[r](j) / scale(j) : basis[r](j);
  Eigen::Index row = 0;
  for (Eigen::Index col = 0; col < p && row < N.rows(); ++col) {
    Eigen::Index piv = row;
    N.col(col).segment(row, N.rows() - row).cwiseAbs().maxCoeff(&piv);
    piv += row;
    if (std::fabs(N(piv, col)) < 1e-9 * N.cwiseAbs().maxCoeff()) continue;
    N.row(row).swap(N.row(piv));
    N.row(row) /= N(row, col);
    for (Eigen::Index r = 0; r < N.rows(); ++r)
      if (r != row) N.row(r) -= N(r, col) * N.row(row);
    ++row;
  }
  const double big = N.cwiseAbs().maxCoeff();
  for (Eigen::Index r = 0; r < N.rows(); ++r) {
    Eigen::VectorXd v = N.row(r).transpose();
    for (Eigen::Index j = 0; j < p; ++j)
      if (std::fabs(v(j)) < 1e-9 * big) v(j) = 0;
    for (Eigen::Index j = 0; j < p; ++j)
      if (v(j) != 0) out.identifiable[static_cast<std::size_t>(j)] = false;
    out.relations.push_back(v);
  }
  return out;
}

std::vector<std::string> Identifiability::sentences() const {
  std::vector<std::string> out;
  for (const auto& v : relations) {
    std::string who, combo;
    for (Eigen::Index j = 0; j < v.size(); ++j) {
      if (v(j) == 0) continue;
      who += (who.empty() ? "" : ", ") + names[static_cast<std::size_t>(j)];
      char buf[64];
      std::snprintf(buf, sizeof buf, "%s%.4g %s", combo.empty() ? (v(j) < 0 ? "-" : "") : (v(j) < 0 ? " - " : " + "),
                    std::fabs(v(j)), names[static_cast<std::size_t>(j)].c_str());
      combo += buf;
    }
    const bool alone = who.find(',') == std::string::npos;
    out.push_back(alone ? who + " leaves every observation unchanged: not identifiable from these positions"
                        : who + " cannot be separated: " + combo + " (um, urad) leaves every observation unchanged");
  }
  return out;
}

}  // namespace probeloop::geometry
