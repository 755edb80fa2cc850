#include "model/fit.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::model {
namespace {

bool endsWith(const std::string& s, const std::string& e) {
  return s.size() >= e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0;
}

// The regression of one channel: y = Phi(tau) theta + fixed, on the training rows.
class ChannelRegression {
 public:
  ChannelRegression(const Campaign& c, const std::string& channel, const std::vector<Effect>& effects, int train_end)
      : c_(c), n_(train_end) {
    ch_ = c.errors.channel(channel);
    if (ch_ < 0) {
      std::string have;
      for (const auto& s : c.errors.channels) have += (have.empty() ? "" : ", ") + s;
      throw InputError(c.errors.file, 0, "no error channel '" + channel + "'; the file has: " + have);
    }
    name_ = c.errors.channels[ch_];
    const int N = c.errors.size();
    y_ = Eigen::Map<const Eigen::VectorXd>(c.errors.values[ch_].data(), N);
    fixed_ = Eigen::VectorXd::Zero(N);
    const double t_train_end = c.errors.t_s[std::max(0, n_ - 1)];
    for (const auto& e : effects) {
      if (e.kind == EffectKind::Offset) continue;
      if (e.kind == EffectKind::Drift) {
        columns_.push_back(&e);
        col_input_.push_back(-1);
        col_lever_.push_back(-1);
        continue;
      }
      const int col = c.inputs.column(e.input);
      if (col < 0) {
        std::string have;
        for (const auto& s : c.inputs.names) have += (have.empty() ? "" : ", ") + s;
        throw InputError(c.inputs.file, 0, name_ + ": " + e.id() + ": no input column '" + e.input + "'; the inputs are: " + have);
      }
      const auto& u = c.inputs.columns[col];
      double lo = u[0], hi = u[0];
      for (std::size_t k = 0; k < u.size() && c.inputs.t_s[k] <= t_train_end; ++k) {
        lo = std::min(lo, u[k]);
        hi = std::max(hi, u[k]);
      }
      if (!(hi - lo > 1e-12 * (1 + std::fabs(hi))))
        throw InputError(c.inputs.file, 0,
                         name_ + ": " + e.id() + ": input '" + e.input + "' is constant (" + formatNumber(lo) +
                             ") over the training span: it cannot explain anything; drop the effect or train on a span where it changes");
      if (e.kind == EffectKind::Expansion) {  // known: a fixed prediction, not a regressor
        const auto r = c.atErrorTimes(regressor(e, c.inputs.t_s, u, 0));
        fixed_ += Eigen::Map<const Eigen::VectorXd>(r.data(), N);
        continue;
      }
      int lever = -1;
      if (!e.lever.empty()) {
        lever = c.inputs.column(e.lever);
        if (lever < 0) {
          std::string have;
          for (const auto& s : c.inputs.names) have += (have.empty() ? "" : ", ") + s;
          throw InputError(c.inputs.file, 0, name_ + ": " + e.id() + ": no input column '" + e.lever + "' for the lever; the inputs are: " + have);
        }
      }
      columns_.push_back(&e);
      col_input_.push_back(col);
      col_lever_.push_back(lever);
      if (e.hasTimeConstant()) nonlinear_.push_back(static_cast<int>(columns_.size()) - 1);
    }
  }

  int linearCount() const { return 1 + static_cast<int>(columns_.size()); }
  int nonlinearCount() const { return static_cast<int>(nonlinear_.size()); }
  const std::vector<int>& nonlinear() const { return nonlinear_; }
  const Effect& columnEffect(int j) const { return *columns_[j]; }
  int samples() const { return static_cast<int>(y_.size()); }
  const std::string& name() const { return name_; }
  int channelIndex() const { return ch_; }
  const Eigen::VectorXd& y() const { return y_; }
  const Eigen::VectorXd& fixed() const { return fixed_; }

  // The design on all samples for the time constants tau (one per nonlinear column).
  Eigen::MatrixXd design(const std::vector<double>& tau) const {
    const int N = samples();
    Eigen::MatrixXd X(N, linearCount());
    X.col(0).setOnes();
    for (std::size_t j = 0; j < columns_.size(); ++j) X.col(1 + j) = column(static_cast<int>(j), tauOf(static_cast<int>(j), tau));
    return X;
  }

  Eigen::VectorXd column(int j, double tau) const {
    const Effect& e = *columns_[j];
    const int N = samples();
    std::vector<double> r;
    if (e.kind == EffectKind::Drift) {
      r.resize(N);
      for (int k = 0; k < N; ++k) r[k] = (c_.errors.t_s[k] - c_.inputs.t_s[0]) / 3600.0;
    } else {
      r = c_.atErrorTimes(regressor(e, c_.inputs.t_s, c_.inputs.columns[col_input_[j]], tau));
      if (col_lever_[j] >= 0) {  // acting over a distance: the regressor times the lever there
        const auto L = c_.atErrorTimes(c_.inputs.columns[col_lever_[j]]);
        for (int k = 0; k < N; ++k) r[k] *= L[k];
      }
    }
    return Eigen::Map<const Eigen::VectorXd>(r.data(), N);
  }

  double tauOf(int j, const std::vector<double>& tau) const {
    for (std::size_t i = 0; i < nonlinear_.size(); ++i)
      if (nonlinear_[i] == j) return tau[i];
    return 0;
  }

  // Least squares on the training rows; returns theta and fills the training residual.
  Eigen::VectorXd solve(const Eigen::MatrixXd& X, Eigen::VectorXd* residual = nullptr) const {
    const auto A = X.topRows(n_);
    const Eigen::VectorXd b = y_.head(n_) - fixed_.head(n_);
    Eigen::VectorXd scale = A.colwise().norm().transpose();
    for (int j = 0; j < scale.size(); ++j)
      if (!(scale(j) > 0)) scale(j) = 1;
    const Eigen::MatrixXd As = A * scale.cwiseInverse().asDiagonal();
    Eigen::VectorXd theta = As.colPivHouseholderQr().solve(b).cwiseQuotient(scale);
    if (residual) *residual = b - A * theta;
    return theta;
  }

  double ssr(const std::vector<double>& tau) const {
    Eigen::VectorXd r;
    solve(design(tau), &r);
    return r.squaredNorm();
  }

  int trainRows() const { return n_; }

 private:
  const Campaign& c_;
  int n_;
  int ch_ = -1;
  std::string name_;
  Eigen::VectorXd y_, fixed_;
  std::vector<const Effect*> columns_;
  std::vector<int> col_lever_;  // per column: the lever's inputs.csv column (-1: none)
  std::vector<int> col_input_, nonlinear_;  // per column: its inputs.csv column (-1: drift); the lag/transient columns
};

struct VarProResidual {
  const ChannelRegression* reg;
  bool operator()(double const* const* p, double* out) const {
    std::vector<double> tau(reg->nonlinearCount());
    for (std::size_t i = 0; i < tau.size(); ++i) tau[i] = std::exp(p[0][i]);
    Eigen::VectorXd r;
    reg->solve(reg->design(tau), &r);
    for (int k = 0; k < r.size(); ++k) out[k] = r(k);
    return true;
  }
};

std::string hours(double s) { return formatNumber(s / 3600.0, 1) + " h"; }

}  // namespace

std::string inputUnit(const std::string& c) {
  if (endsWith(c, "_C") || endsWith(c, "_K")) return "K";
  if (endsWith(c, "_rpm")) return "rpm";
  if (endsWith(c, "_mm_per_min")) return "(mm/min)";
  if (endsWith(c, "_mm")) return "mm";
  if (endsWith(c, "_um")) return "um";
  if (endsWith(c, "_N")) return "N";
  if (endsWith(c, "_on")) return "on";
  if (c == "tool_changes") return "change";
  return "unit";
}

int trainingEnd(int samples, double fraction) {
  return std::clamp(static_cast<int>(std::lround(fraction * samples)), 1, samples);
}

ChannelFit fitChannel(const Campaign& c, const std::string& channel, const std::vector<Effect>& effects, int train_end) {
  // Full rank first: it needs no data beyond the counts, and says how much more to measure.
  int p = 1;
  for (const auto& e : effects)  // a fixed time constant is not a parameter
    p += (e.fitsGain() && e.kind != EffectKind::Offset ? 1 : 0) + (e.hasTimeConstant() && !e.tau_fixed ? 1 : 0);
  const int n = train_end, N = c.errors.size();
  if (n <= p) {
    const double dt = N > 1 ? (c.errors.t_s.back() - c.errors.t_s.front()) / (N - 1) : 0;
    const int more = p + 1 - n;
    throw InputError(c.errors.file, 0,
 channel + ": the training span has " + std::to_string(n) + " samples for " + std::to_string(p) +
                         " parameters; a full-rank fit needs at least " + std::to_string(p + 1) + " (seed 004 Ch. 6): " +
                         std::to_string(more) + " more samples, about " + hours(more * dt) +
                         " more campaign at this cycle interval");
  }
  ChannelRegression reg(c, channel, effects, train_end);
  ChannelFit fit;
  fit.channel = reg.name();
  fit.unit = channelUnit(fit.channel);
  const int m = reg.linearCount(), q = reg.nonlinearCount();
  fit.n_train = n;
  fit.parameters = p;

  // Time constants: a grid start per tau, then Ceres on ln tau (variable projection).
  const double span = c.errors.t_s[n - 1] - c.inputs.t_s.front();
  const double lo = std::max(c.inputs.step_s, 60.0), hi = std::max(4 * span, 2 * lo);
  std::vector<double> tau(q);
  for (int i = 0; i < q; ++i) {
    const Effect& e = reg.columnEffect(reg.nonlinear()[i]);
    tau[i] = e.tau_fixed ? *e.tau_s : e.tau_s ? std::clamp(*e.tau_s, lo, hi) : std::sqrt(lo * hi);
  }
  for (int i = 0; i < q; ++i) {
    // The grid runs even when the file gives a start: a start far from the optimum (a
    // median over channels, a guess) must not trap Ceres in a flat valley.
    const Effect& e = reg.columnEffect(reg.nonlinear()[i]);
    if (e.tau_fixed) continue;
    double best = reg.ssr(tau), best_tau = tau[i];
    constexpr int kGrid = 16;
    for (int g = 0; g < kGrid; ++g) {
      tau[i] = lo * std::pow(hi / lo, (g + 0.5) / kGrid);
      const double s = reg.ssr(tau);
      if (s < best) best = s, best_tau = tau[i];
    }
    tau[i] = best_tau;
  }
  std::vector<int> free;
  for (int i = 0; i < q; ++i)
    if (!reg.columnEffect(reg.nonlinear()[i]).tau_fixed) free.push_back(i);
  if (!free.empty()) {
    std::vector<double> logtau(q);
    for (int i = 0; i < q; ++i) logtau[i] = std::log(tau[i]);
    auto* cost = new ceres::DynamicNumericDiffCostFunction<VarProResidual, ceres::CENTRAL>(new VarProResidual{&reg});
    cost->AddParameterBlock(q);
    cost->SetNumResiduals(n);
    ceres::Problem problem;
    problem.AddResidualBlock(cost, nullptr, logtau.data());
    for (int i = 0; i < q; ++i) {
      problem.SetParameterLowerBound(logtau.data(), i, std::log(lo));
      problem.SetParameterUpperBound(logtau.data(), i, std::log(hi));
    }
    if (static_cast<int>(free.size()) < q) {
      std::vector<int> fixed_idx;
      for (int i = 0; i < q; ++i)
        if (reg.columnEffect(reg.nonlinear()[i]).tau_fixed) fixed_idx.push_back(i);
      problem.SetManifold(logtau.data(), new ceres::SubsetManifold(q, fixed_idx));
    }
    ceres::Solver::Options opt;
    opt.linear_solver_type = ceres::DENSE_QR;
    opt.logging_type = ceres::SILENT;
    opt.minimizer_progress_to_stdout = false;
    opt.num_threads = 1;
    opt.max_num_iterations = 50;
    ceres::Solver::Summary summary;
    ceres::Solve(opt, &problem, &summary);
    for (int i = 0; i < q; ++i) tau[i] = std::exp(logtau[i]);
  }

  // Final linear solve, identifiability, and the full covariance.
  const Eigen::MatrixXd X = reg.design(tau);
  Eigen::VectorXd res;
  const Eigen::VectorXd theta = reg.solve(X, &res);
  // Columns: the linear parameters, then the free ln tau (a fixed tau is not a parameter).
  Eigen::MatrixXd J(n, p);
  J.leftCols(m) = X.topRows(n);
  std::vector<std::string> names{"offset"};
  for (int j = 0; j < m - 1; ++j) names.push_back("gain of " + reg.columnEffect(j).id());
  std::vector<int> col_of_tau(q, -1);
  for (int i = 0, k = m; i < q; ++i) {
    const int j = reg.nonlinear()[i];
    if (reg.columnEffect(j).tau_fixed) continue;
    constexpr double h = 1e-4;
    const Eigen::VectorXd d = (reg.column(j, tau[i] * std::exp(h)) - reg.column(j, tau[i] * std::exp(-h))) / (2 * h);
    J.col(k) = theta(1 + j) * d.head(n);
    names.push_back("time constant of " + reg.columnEffect(j).id());
    col_of_tau[i] = k++;
  }
  Eigen::VectorXd scale = J.colwise().norm().transpose();
  for (int j = 0; j < p; ++j)
    if (!(scale(j) > 0)) scale(j) = 1;
  const Eigen::MatrixXd Js = J * scale.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js, Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  const double cond = sv(0) / std::max(sv(p - 1), 1e-300);
  if (!(cond < 1e10)) {
    int worst = 0;
    svd.matrixV().col(p - 1).cwiseAbs().maxCoeff(&worst);
    throw InputError(c.errors.file, 0,
                     fit.channel + ": the " + names[worst] + " cannot be identified from the training span (condition number " +
                         formatNumber(cond, 0) + "): its regressor is flat or collinear with the others there; " +
                         "train on a span where the inputs vary independently, or drop the effect");
  }
  const double dof = n - p;
  const double s2 = res.squaredNorm() / dof;
  const Eigen::MatrixXd Vinv = svd.matrixV() * sv.cwiseInverse().cwiseAbs2().asDiagonal() * svd.matrixV().transpose();
  const Eigen::MatrixXd cov = s2 * scale.cwiseInverse().asDiagonal() * Vinv * scale.cwiseInverse().asDiagonal();
  fit.sigma = std::sqrt(s2);
  // Rissanen's MDL, V_N (1 + p ln n / n): seed 004 Eq. 4.23 penalised by the parameter count
  // (the printed form does not penalise order; docs/decisions.md).
  fit.mdl = res.squaredNorm() / n * (1 + p * std::log(static_cast<double>(n)) / n);

  // Parameters in the field's units.
  FittedEffect off;
  off.effect.kind = EffectKind::Offset;
  off.parameters.push_back({"c", fit.unit, theta(0), std::sqrt(cov(0, 0))});
  fit.effects.push_back(off);
  for (int j = 0; j < m - 1; ++j) {
    FittedEffect fe;
    fe.effect = reg.columnEffect(j);
    std::string gunit = fe.effect.kind == EffectKind::Drift ? fit.unit + "/h" : fit.unit + "/" + inputUnit(fe.effect.input);
    if (!fe.effect.lever.empty()) gunit = fit.unit + "/(" + inputUnit(fe.effect.input) + " " + inputUnit(fe.effect.lever) + ")";
    fe.parameters.push_back({fe.effect.kind == EffectKind::Drift ? "b" : "k", gunit, theta(1 + j), std::sqrt(cov(1 + j, 1 + j))});
    for (int i = 0; i < q; ++i)
      if (reg.nonlinear()[i] == j) {
        fe.effect.tau_s = tau[i];
        const int k = col_of_tau[i];
        fe.parameters.push_back({k < 0 ? "tau (fixed)" : "tau", "s", tau[i], k < 0 ? 0.0 : tau[i] * std::sqrt(cov(k, k))});
      }
    fit.effects.push_back(fe);
  }
  for (const auto& e : effects)
    if (e.kind == EffectKind::Expansion) {
      FittedEffect fe;
      fe.effect = e;
      fe.parameters.push_back({"alpha (fixed)", "um/(m K)", e.alpha_um_per_m_K, 0});
      fe.parameters.push_back({"L (fixed)", "mm", e.length_mm, 0});
      fit.effects.push_back(fe);
    }

  const Eigen::VectorXd pred = X * theta + reg.fixed();
  fit.predicted.assign(pred.data(), pred.data() + N);
  const auto& y = c.errors.values[reg.channelIndex()];
  fit.training = indicators({y.begin(), y.begin() + n}, {fit.predicted.begin(), fit.predicted.begin() + n});
  fit.has_validation = n < N;
  if (fit.has_validation)
    fit.validation = indicators({y.begin() + n, y.end()}, {fit.predicted.begin() + n, fit.predicted.end()});
  std::vector<double> us;
  for (double U : c.errors.U[reg.channelIndex()])
    if (U > 0) us.push_back(U / 2);
  if (!us.empty()) {
    std::nth_element(us.begin(), us.begin() + us.size() / 2, us.end());
    fit.u_measurement = us[us.size() / 2];
  }
  return fit;
}

}  // namespace probeloop::model
