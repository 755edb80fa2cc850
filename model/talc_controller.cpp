#include "model/talc_controller.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "core/error.hpp"
#include "model/dataset.hpp"
#include "model/talc_detail.hpp"

namespace probeloop::model {
namespace {

using talc_detail::fmt;
using talc_detail::hours;
using talc_detail::joined;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A fit that can fail (rank, constant input): the reason instead of an exception.
struct Attempt {
  std::optional<ArxModel> model;
  std::string reason;
};

Attempt tryFit(const Eigen::VectorXd& y, const Eigen::MatrixXd& u, const ArxOrders& o,
               const std::vector<std::string>& names, const Eigen::VectorXd& w) {
  Attempt a;
  try {
    a.model = fitArx(y, u, o, names, &w);
  } catch (const GeometryError& e) {
    a.reason = e.what();
  } catch (const InputError& e) {
    a.reason = e.what();
  }
  return a;
}

// Largest |pole| of A(q) = 1 + a_1 q^-1 + ... (roots of z^na + a_1 z^(na-1) + ... + a_na).
double spectralRadius(const ArxModel& m) {
  const auto n = static_cast<Eigen::Index>(m.a.size());
  if (n == 0) return 0;
  Eigen::MatrixXd comp = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) comp(0, i) = -m.a[static_cast<std::size_t>(i)];
  for (Eigen::Index i = 1; i < n; ++i) comp(i, i - 1) = 1;
  return comp.eigenvalues().cwiseAbs().maxCoeff();
}

Eigen::VectorXd head(const std::vector<double>& v, int n) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), n);
}

}  // namespace

const char* talcPhaseName(TalcPhase p) {
  switch (p) {
    case TalcPhase::calibration: return "CP";
    case TalcPhase::compensation: return "compensation";
    case TalcPhase::no_good: return "NG";
  }
  return "?";
}

TalcController::TalcController(const TalcOptions& o, std::vector<std::string> channels,
                               std::vector<std::string> inputs, double grid_s, double t0_s)
    : o_(o), channels_(std::move(channels)), inputs_(std::move(inputs)), D_(grid_s), t0_(t0_s) {
  auto positive = [](double v, const char* what) {
    if (!(v > 0) || !std::isfinite(v))
      throw InputError("", 0, std::string("TALC: ") + what + " must be a positive number of the stated unit");
  };
  if (!(o.cp_h >= 0) || !std::isfinite(o.cp_h))
    throw InputError("", 0, "TALC: the calibration phase must be >= 0 h (0 = as short as possible)");
  positive(o.post_interval_h, "the post-CP measurement interval (h)");
  positive(o.ng_interval_min, "the NG measurement interval (min)");
  positive(o.limit_linear_um, "the linear action limit (um)");
  positive(o.limit_angular_urad, "the angular action limit (urad = um/m)");
  positive(grid_s, "the prediction grid (s)");
  if (!(o.cycle_duration_s >= 0) || !std::isfinite(o.cycle_duration_s))
    throw InputError("", 0, "TALC: the cycle duration must be >= 0 s");
  if (!(o.update_interval_h >= 0) || !std::isfinite(o.update_interval_h))
    throw InputError("", 0, "TALC: the parameter update interval must be >= 0 h (0 = no periodic update)");
  if (!(o.weight_half_life_h >= 0) || !std::isfinite(o.weight_half_life_h))
    throw InputError("", 0, "TALC: the weight half-life must be >= 0 h (0 = no forgetting)");
  if (o.ng_measurements < 1) throw InputError("", 0, "TALC: an NG phase needs at least 1 measurement");
  if (!(o.predicted_weight >= 0 && o.predicted_weight <= 1))
    throw InputError("", 0, "TALC: the weight of predicted samples must lie in [0, 1] (measured ones weigh 1)");
  if (o.na < 0) throw InputError("", 0, "TALC: na must be >= 0");
  if (channels_.empty()) throw InputError("", 0, "TALC: no error channel to model");

  for (const auto& name : channels_) {
    const std::string unit = channelUnit(name);
    if (unit == "um")
      limit_.push_back(o.limit_linear_um);
    else if (unit == "urad")
      limit_.push_back(o.limit_angular_urad);
    else
      throw InputError("", 0,
                       "TALC: channel " + name + " has unit '" + unit +
                           "'; the action limits are for *_um (linear) and *_urad (angular, 1 urad = 1 um/m)");
  }
  const int r = static_cast<int>(inputs_.size());
  orders_.na = o.na;
  orders_.instantaneous = o.instantaneous;
  orders_.intercept = o.intercept;
  if (o.nb_per_input.empty()) {
    orders_.nb.assign(inputs_.size(), o.nb);
  } else {
    if (o.nb_per_input.size() != inputs_.size())
      throw InputError(
          "", 0,
          "TALC: " + std::to_string(o.nb_per_input.size()) + " input orders for " + std::to_string(r) + " inputs");
    orders_.nb = o.nb_per_input;
  }
  for (int n : orders_.nb)
    if (n < 1) throw InputError("", 0, "TALC: every input order nb must be >= 1");
  L_ = orders_.maxLag();
  int sum_orders = orders_.na;
  for (int n : orders_.nb) sum_orders += n;
  required_s_ = std::max(sum_orders * D_, (L_ + orders_.parameterCount()) * D_);
  cp_s_ = o.cp_h * 3600.0;
  const std::size_t C = channels_.size();
  meas_.assign(C, {});
  S_.assign(C, {});
  pred_.assign(C, {});
}

std::string TalcController::ordersText() const {
  std::ostringstream s;
  s << "na = " << orders_.na << ", nb = ";
  for (std::size_t i = 0; i < orders_.nb.size(); ++i) s << (i ? "/" : "") << orders_.nb[i];
  s << " for " << inputs_.size() << " input" << (inputs_.size() == 1 ? "" : "s")
    << (orders_.intercept ? " and an intercept" : "");
  return s.str();
}

void TalcController::appendInputRow(const std::vector<double>& row) {
  if (row.size() != inputs_.size()) throw std::logic_error("TALC: input row of the wrong width");
  U_.push_back(row);
}

int TalcController::gridIndex(double t_s) const { return static_cast<int>(std::lround((t_s - t0_) / D_)); }

void TalcController::ensureGrid(int k) {
  const auto n = static_cast<std::size_t>(k + 1);
  if (measured_.size() >= n) return;
  measured_.resize(n, 0);
  for (std::size_t q = 0; q < channels_.size(); ++q) {
    meas_[q].resize(n, kNaN);
    S_[q].resize(n, 0.0);
    pred_[q].resize(n, 0.0);
  }
}

Eigen::MatrixXd TalcController::inputMatrix(int rows) const {
  if (rows > inputRows()) throw std::logic_error("TALC: input rows missing for grid index " + std::to_string(rows - 1));
  Eigen::MatrixXd u(rows, static_cast<Eigen::Index>(inputs_.size()));
  for (int k = 0; k < rows; ++k)
    for (std::size_t i = 0; i < inputs_.size(); ++i) u(k, static_cast<Eigen::Index>(i)) = U_[static_cast<std::size_t>(k)][i];
  return u;
}

bool TalcController::wants(double t_s) const {
  switch (phase_) {
    case TalcPhase::calibration: return true;
    case TalcPhase::no_good: return t_s >= next_ng_ - tolerance();
    case TalcPhase::compensation: return t_s >= next_post_ - tolerance();
  }
  return true;
}

double TalcController::nextDue() const {
  switch (phase_) {
    case TalcPhase::calibration: return last_k_ < 0 ? t0_ : gridTime(last_k_ + 1);
    case TalcPhase::no_good: return next_ng_;
    case TalcPhase::compensation: return next_post_;
  }
  return t0_;
}

// The CP's stored series up to kend: measured values, gaps interpolated (weighted as predicted).
void TalcController::cpSeries(std::size_t q, int kend, Eigen::VectorXd& y, Eigen::VectorXd& w) const {
  y.resize(kend + 1);
  w.resize(kend + 1);
  const std::vector<double>& m = meas_[q];
  auto at = [&](int k) { return static_cast<std::size_t>(k) < m.size() ? m[static_cast<std::size_t>(k)] : kNaN; };
  int prev = -1;
  for (int k = 0; k <= kend; ++k) {
    if (!std::isfinite(at(k))) continue;
    y(k) = at(k);
    w(k) = 1;
    for (int i = prev + 1; i < k; ++i) {
      y(i) = prev < 0 ? at(k) : at(prev) + (at(k) - at(prev)) * (i - prev) / double(k - prev);
      w(i) = o_.predicted_weight;
    }
    prev = k;
  }
  for (int i = prev + 1; i <= kend; ++i) {
    y(i) = prev < 0 ? 0.0 : at(prev);
    w(i) = o_.predicted_weight;
  }
}

bool TalcController::fitCp(int kend, std::vector<ArxModel>& out, std::string& why) const {
  out.clear();
  const Eigen::MatrixXd u = inputMatrix(kend + 1);
  for (std::size_t q = 0; q < channels_.size(); ++q) {
    Eigen::VectorXd y, w;
    cpSeries(q, kend, y, w);
    Attempt a = tryFit(y, u, orders_, inputs_, w);
    if (!a.model) {
      why = channels_[q] + ": " + a.reason;
      return false;
    }
    out.push_back(*a.model);
  }
  return true;
}

bool TalcController::calibrationFits(int k, std::string& why) const {
  std::vector<ArxModel> probe;
  return fitCp(k, probe, why);
}

// A fit whose A(q) has a pole on or outside the unit circle diverges between measurements in
// simulation mode: said in the event, never silently.
std::string TalcController::stability(const std::vector<ArxModel>& ms) const {
  std::string s;
  for (std::size_t q = 0; q < ms.size(); ++q) {
    const double rho = spectralRadius(ms[q]);
    if (rho >= 1) s += (s.empty() ? "; unstable: " : ", ") + channels_[q] + " (|pole| " + fmt(rho, 3) + ")";
  }
  return s;
}

bool TalcController::closeCalibration(int k, double cp_s, std::string& why) {
  if (phase_ != TalcPhase::calibration) throw std::logic_error("TALC: the calibration phase is already closed");
  std::vector<ArxModel> ms;
  if (!fitCp(k, ms, why)) return false;
  ensureGrid(k);
  for (std::size_t q = 0; q < channels_.size(); ++q) {
    Eigen::VectorXd y, w;
    cpSeries(q, k, y, w);
    for (int i = 0; i <= k; ++i) S_[q][static_cast<std::size_t>(i)] = y(i);
  }
  models_ = std::move(ms);
  last_update_k_ = k;
  phase_ = TalcPhase::compensation;
  cp_end_s_ = cp_s;
  done_ = k;
  last_update_ = gridTime(k);
  next_post_ = t0_ + cp_s + o_.post_interval_h * 3600.0;
  events_.push_back({gridTime(k), "", 0, "first fit" + stability(models_)});
  return true;
}

// Refit every channel on the stored series up to kend (WLS, Eq. 4.20); effective from t_effect.
Eigen::VectorXd TalcController::updateWeights(int kend) const {
  Eigen::VectorXd w(kend + 1);
  for (int k = 0; k <= kend; ++k) {
    w(k) = measured_[static_cast<std::size_t>(k)] ? 1.0 : o_.predicted_weight;
    if (o_.weight_half_life_h > 0) w(k) *= std::exp2(-(gridTime(kend) - gridTime(k)) / (o_.weight_half_life_h * 3600.0));
  }
  return w;
}

void TalcController::update(int kend, double t_effect, bool after_ng) {
  const Eigen::VectorXd w = updateWeights(kend);
  const Eigen::MatrixXd u = inputMatrix(kend + 1);
  std::vector<ArxModel> next;
  for (std::size_t q = 0; q < channels_.size(); ++q) {
    Attempt a = tryFit(head(S_[q], kend + 1), u, orders_, inputs_, w);
    if (!a.model) {
      events_.push_back({t_effect, "", 0, "update failed, previous model kept: " + channels_[q] + ": " + a.reason});
      return;
    }
    next.push_back(*a.model);
  }
  models_ = std::move(next);
  last_update_k_ = kend;
  events_.push_back({t_effect, "", 0, (after_ng ? "update after NG" : "periodic update") + stability(models_)});
  (after_ng ? updates_after_ng_ : updates_periodic_)++;
}

// Predictions up to grid index kto (simulation mode from the stored series), with the
// periodic updates that fall due on the way.
void TalcController::advance(int kto) {
  if (kto <= done_) return;
  ensureGrid(kto);
  const double upd_s = o_.update_interval_h * 3600.0;
  for (int k = done_ + 1; k <= kto; ++k) {
    if (phase_ != TalcPhase::no_good && upd_s > 0 && gridTime(k) >= last_update_ + upd_s - tolerance()) {
      update(k - 1, gridTime(k), false);
      last_update_ = gridTime(k);
    }
    if (k >= inputRows()) throw std::logic_error("TALC: input row " + std::to_string(k) + " is not known yet");
    for (std::size_t q = 0; q < channels_.size(); ++q) {
      // A model fitted before an input was added reads the first inputs of each row only.
      const ArxModel& m = models_[q];
      const int Lm = m.orders.maxLag();
      const auto r = static_cast<Eigen::Index>(m.orders.nb.size());
      Eigen::MatrixXd window(Lm + 1, r);
      for (int i = 0; i <= Lm; ++i)
        for (Eigen::Index c = 0; c < r; ++c)
          window(i, c) = U_[static_cast<std::size_t>(k - Lm + i)][static_cast<std::size_t>(c)];
      Eigen::VectorXd past(Lm);
      for (int i = 0; i < Lm; ++i) past(i) = S_[q][static_cast<std::size_t>(k - Lm + i)];
      const double v = simulate(m, window, past)(Lm);
      pred_[q][static_cast<std::size_t>(k)] = S_[q][static_cast<std::size_t>(k)] = v;
    }
  }
  done_ = kto;
}

void TalcController::addInput(const std::string& label, const std::vector<double>& values, int nb) {
  if (values.size() != U_.size()) throw std::logic_error("TALC: an added input needs a value for every known grid index");
  if (nb < 1) throw InputError("", 0, "TALC: every input order nb must be >= 1");
  inputs_.push_back(label);
  orders_.nb.push_back(nb);
  for (std::size_t k = 0; k < U_.size(); ++k) U_[k].push_back(values[k]);
  L_ = orders_.maxLag();
  events_.push_back({U_.empty() ? t0_ : gridTime(inputRows() - 1), "", 0, "input added: " + label + " (used from the next update)"});
}

std::optional<TalcController::CandidateScore> TalcController::scoreCandidate(const std::vector<double>& values,
                                                                              int kend) const {
  if (kend < 0 || static_cast<int>(values.size()) <= kend || kend >= inputRows()) return std::nullopt;
  const Eigen::VectorXd w = updateWeights(kend);
  Eigen::MatrixXd u = inputMatrix(kend + 1);
  Eigen::MatrixXd uc(u.rows(), u.cols() + 1);
  uc << u, Eigen::Map<const Eigen::VectorXd>(values.data(), kend + 1);
  ArxOrders with = orders_;
  with.nb.push_back(o_.nb);
  std::vector<std::string> names = inputs_;
  names.push_back("candidate");
  auto mdl = [](const ArxModel& m) {
    const double d = static_cast<double>(m.theta.size()), N = m.rows;
    return m.sigma * m.sigma * (1 + d * std::log(N) / N);
  };
  CandidateScore s;
  for (std::size_t q = 0; q < channels_.size(); ++q) {
    const Eigen::VectorXd y = head(S_[q], kend + 1);
    const Attempt a = tryFit(y, u, orders_, inputs_, w), b = tryFit(y, uc, with, names, w);
    if (!a.model || !b.model) return std::nullopt;
    s.mdl_without.push_back(mdl(*a.model));
    s.mdl_with.push_back(mdl(*b.model));
  }
  return s;
}

std::vector<double> TalcController::predict(int k) {
  if (phase_ == TalcPhase::calibration) return {};
  if (k < 0) throw std::logic_error("TALC: grid index before the start");
  advance(k);
  std::vector<double> out;
  for (std::size_t q = 0; q < channels_.size(); ++q) out.push_back(pred_[q][static_cast<std::size_t>(k)]);
  return out;
}

std::vector<double> TalcController::measure(double t, const std::vector<double>& values) {
  if (values.size() != channels_.size()) throw std::logic_error("TALC: measurement of the wrong width");
  const int k = gridIndex(t);
  if (k < last_k_ || k < 0) throw std::logic_error("TALC: measurements out of time order");
  last_k_ = k;
  const double tol = tolerance();
  if (phase_ == TalcPhase::calibration) {
    ensureGrid(k);
    for (std::size_t q = 0; q < channels_.size(); ++q) meas_[q][static_cast<std::size_t>(k)] = values[q];
    measured_[static_cast<std::size_t>(k)] = 1;
    return {};
  }
  advance(k);
  std::vector<double> res(channels_.size());
  for (std::size_t q = 0; q < channels_.size(); ++q) res[q] = values[q] - pred_[q][static_cast<std::size_t>(k)];
  measured_[static_cast<std::size_t>(k)] = 1;
  for (std::size_t q = 0; q < channels_.size(); ++q) S_[q][static_cast<std::size_t>(k)] = values[q];  // state update
  auto beyond = [&](std::size_t q) { return std::fabs(res[q]) > limit_[q]; };
  const double post_s = o_.post_interval_h * 3600.0, ng_s = o_.ng_interval_min * 60.0;
  if (phase_ == TalcPhase::no_good) {
    for (std::size_t q = 0; q < channels_.size(); ++q)
      if (beyond(q)) events_.push_back({t, channels_[q], res[q], "ignored (NG active)"});
    if (next_ng_ <= t + tol) next_ng_ += ng_s * (std::floor((t + tol - next_ng_) / ng_s) + 1);  // no loop: a tiny interval cannot spin
    if (++ng_count_ == o_.ng_measurements) {
      phase_ = TalcPhase::compensation;
      update(k, t, true);
      last_update_ = t;
      next_post_ = t + post_s;
    }
    return res;
  }
  if (next_post_ <= t + tol) next_post_ += post_s * (std::floor((t + tol - next_post_) / post_s) + 1);
  bool start = false;
  for (std::size_t q = 0; q < channels_.size(); ++q)
    if (beyond(q)) {
      start = true;
      events_.push_back({t, channels_[q], res[q], "NG start"});
    }
  if (start) {
    phase_ = TalcPhase::no_good;
    ng_count_ = 0;
    next_ng_ = t + ng_s;
    ng_phases_++;
  }
  return res;
}

}  // namespace probeloop::model
