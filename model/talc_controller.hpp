// Thermal Adaptive Learning Control as a state machine (seed 004 Ch. 6, notes §7.1): fed the
// input rows of the prediction grid and the measurements as they happen, it decides the
// phase (calibration, compensation, No-Good), fits and updates the per-channel ARX models,
// predicts the errors on the grid (simulation mode, the measured value stored instead of
// the prediction where one exists) and says when it wants the next measurement. The offline
// replay (model/talc.hpp) and the live loop (`campaign run`) both drive this one machine.
//
// Grid: t0 + k D (D = the calibration phase's measurement interval, as in the thesis: "a
// prediction is made at the same interval as the CP measurements"); a measurement belongs
// to grid index round((t - t0) / D). Input row k (inputs at t0 + k D, already transformed:
// a temperature as its change since t0) must be appended before index k is predicted.
//
// Schedule (tolerance D/4, all as the replay documents in model/talc.hpp):
// - calibration (CP): every measurement; compensation off. The driver closes it
//   (closeCalibration: the first fit) where its rule says: the replay at the last measurement
//   within the CP length, or at the first grid index that identifies every channel (cp_h = 0,
//   "as short as possible"); the live loop the same, causally (campaign/live_loop.hpp). The CP
//   series is the measurements with gaps interpolated (those samples weigh predicted_weight).
// - compensation: measurements wanted at t_cp_end + i * post interval; after one, any
//   |measured - predicted| beyond its action limit starts a No-Good phase of ng_measurements
//   at the NG interval (exceedances inside it are logged as ignored); all channels are
//   refitted (WLS Eq. 4.20, measured rows weigh 1, predicted ones predicted_weight) after the
//   NG's last measurement and every update_interval_h after the previous update.
// - a measurement that arrives when none is wanted (a cycle run by hand) is still taken: the
//   machine measured it. The replay asks wants() first and scores what TALC would not take.
//
// Contract: measurements in non-decreasing time; index k predicted only once input rows up
// to k exist (std::logic_error otherwise: a driver's bug); no NaN ever leaves predict().
#pragma once
#include <Eigen/Dense>
#include <optional>
#include <string>
#include <vector>

#include "model/arx.hpp"
#include "model/talc.hpp"

namespace probeloop::model {

enum class TalcPhase { calibration, compensation, no_good };
const char* talcPhaseName(TalcPhase p);  // "CP", "compensation", "NG"

class TalcController {
 public:
  // channels: error channel names (unit from the suffix: *_um, *_urad); inputs: labels of the
  // input columns. Throws InputError for options the replay refuses (before any data).
  TalcController(const TalcOptions& o, std::vector<std::string> channels, std::vector<std::string> inputs,
                 double grid_s, double t0_s);

  void appendInputRow(const std::vector<double>& row);  // row k = inputs at t0 + k D
  int inputRows() const { return static_cast<int>(U_.size()); }

  int gridIndex(double t_s) const;
  double gridTime(int k) const { return t0_ + k * D_; }
  double gridStep() const { return D_; }
  double tolerance() const { return D_ / 4; }

  TalcPhase phase() const { return phase_; }
  bool compensating() const { return phase_ != TalcPhase::calibration; }
  // Would TALC take a measurement at t (CP: always).
  bool wants(double t_s) const;
  // Nominal time of the next wanted measurement (CP: the next grid time after the last one).
  double nextDue() const;

  // Predicted errors at grid index k (advancing the simulation and any periodic update that
  // falls due on the way); empty during the CP.
  std::vector<double> predict(int k);

  // A measurement of every channel (uncompensated values) at t. Returns the residuals
  // measured - predicted (empty in the CP). Events are appended to events().
  std::vector<double> measure(double t_s, const std::vector<double>& values);

  // The replay's fixed-CP rule: close the CP at grid index k (the last CP measurement's);
  // false (nothing changed) when a channel's fit fails there, `why` says which and why.
  bool closeCalibration(int k, double cp_s, std::string& why);
  // Every channel's CP fit at grid index k succeeds (models not kept).
  bool calibrationFits(int k, std::string& why) const;

  // An input added while TALC runs (the live loop's `campaign add-input`): its values at every
  // grid index known so far; later rows carry it too. The models in use keep their inputs (the
  // first ones of each row) until the next update, which fits with it.
  void addInput(const std::string& label, const std::vector<double>& values, int nb);
  const std::vector<std::string>& inputs() const { return inputs_; }

  // What one more input would give each channel at the last update's data (the stored series
  // up to grid index kend, the WLS weights of an update): Rissanen's MDL criterion
  // sigma^2 (1 + d ln N / N) of the fit without and with it (d parameters, N rows). Empty when
  // a fit fails (a constant or unidentifiable candidate).
  struct CandidateScore {
    std::vector<double> mdl_without, mdl_with;
  };
  std::optional<CandidateScore> scoreCandidate(const std::vector<double>& values, int kend) const;
  int lastUpdateIndex() const { return last_update_k_; }

  const std::vector<TalcEvent>& events() const { return events_; }
  void addEvent(const TalcEvent& e) { events_.push_back(e); }  // a driver's own (e.g. the CP extended)
  const std::vector<std::string>& channels() const { return channels_; }
  const std::vector<double>& limits() const { return limit_; }
  const std::vector<ArxModel>& models() const { return models_; }
  const ArxOrders& orders() const { return orders_; }
  double cpRequiredS() const { return required_s_; }
  double cpEndS() const { return cp_end_s_; }  // since t0; 0 while in the CP
  int ngPhases() const { return ng_phases_; }
  int updatesAfterNg() const { return updates_after_ng_; }
  int updatesPeriodic() const { return updates_periodic_; }
  std::string ordersText() const;

 private:
  void cpSeries(std::size_t q, int kend, Eigen::VectorXd& y, Eigen::VectorXd& w) const;
  bool fitCp(int kend, std::vector<ArxModel>& out, std::string& why) const;
  Eigen::MatrixXd inputMatrix(int rows) const;
  void update(int kend, double t_effect, bool after_ng);
  Eigen::VectorXd updateWeights(int kend) const;
  void advance(int kto);
  std::string stability(const std::vector<ArxModel>& ms) const;
  void ensureGrid(int k);

  TalcOptions o_;
  std::vector<std::string> channels_, inputs_;
  std::vector<double> limit_;
  ArxOrders orders_;
  int L_ = 0;
  double D_ = 0, t0_ = 0, required_s_ = 0, cp_s_ = 0;

  std::vector<std::vector<double>> U_;        // input rows
  std::vector<std::vector<double>> meas_;     // [channel][k] measured (NaN where none)
  std::vector<std::vector<double>> S_;        // [channel][k] stored series
  std::vector<std::vector<double>> pred_;     // [channel][k] predictions
  std::vector<char> measured_;                // [k]
  int last_k_ = -1;                           // grid index of the last measurement

  TalcPhase phase_ = TalcPhase::calibration;
  std::vector<ArxModel> models_;
  std::vector<TalcEvent> events_;
  double cp_end_s_ = 0, last_update_ = 0, next_post_ = 0, next_ng_ = 0;
  int ng_count_ = 0, done_ = -1, last_update_k_ = -1;
  int ng_phases_ = 0, updates_after_ng_ = 0, updates_periodic_ = 0;
};

}  // namespace probeloop::model
