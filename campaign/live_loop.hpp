// The live TALC loop on a campaign store (seed 004 Ch. 6; docs/model.md#talc-live): the store's
// evaluated cycles and input samples drive model::TalcController, in time order, as they
// arrive; every grid step's prediction (the offsets' parameters), every measurement's
// residual, every event, model version and phase change is written to the store in the same
// transaction as the step, so a run killed at any instant and started again goes on from
// where the store says, and ends with the same content as an uninterrupted run.
//
// Time order (what makes the result a function of the data, not of when they were read):
// - t0 = the reference cycle's time; the grid t0 + k D (D = the plan's cycle period, or given);
// - grid step k is processed once an input sample at or after t0 + k D is stored (its input
//   row is interpolated between the samples around it, as the replay does; call that sample's
//   time s), no cycle that is still being logged has a point before s, and, while a log has a
//   torn last line, its last complete point is not before s; its prediction is issued at the time of the data that completed it: s, or the
//   last point of a cycle that was being logged at s; it applies from that instant. This
//   assumes the controller's log reaches its file no later than the data logger's samples of
//   later times (a line in flight shows as a torn last line, which holds the step);
// - a final cycle's measurement (grid index round((t - t0) / D)) is processed after its grid
//   step and before the next one. With `finished`, the input rows are held at their ends and
//   nothing waits for more.
// - the calibration phase closes causally at the step where the replay's rule is decided: a
//   fixed CP at its last measurement (t - t0 <= CP + D/4), once a later step shows it was the
//   last; "as short as possible" (cp_h = 0) at the first grid index that identifies every
//   channel. A fixed CP whose fit fails goes on (event "calibration phase extended") and
//   closes at the next measurement that identifies every channel.
// Measurements (docs/model.md#talc-live):
// - with offsets_applied, the controller applied the issued offsets while the cycle ran, so
//   the cycle measured the residual: the uncompensated value fed to TALC is the measured one
//   plus the prediction in effect at the cycle's time;
// - requested_only: a cycle TALC did not ask for (a dense log replayed) is stored and scored
//   (its residual against the prediction) but not fed; then the live loop gives the replay's
//   result (model/talc.hpp) on the same data and grid.
// Inputs added while it runs (`campaign add-input`, after a diagnosis named one): a request
// the loop takes at its next pass, applied between two steps (recorded with the number of
// steps before it, so a rebuild applies it at the same place) and used from the next update.
// At every model version the loop scores each input the models do not use (the MDL criterion
// of each channel's WLS fit without and with it, on the update's data) and stores which one
// it would add, with the command (the dashboard shows it).
// Contract: the options are stored at the first run; a later run with other options is an
// InputError naming the field (the store is not touched). Errors of the data (an input column
// TALC needs that the stream lacks) are InputErrors before anything is written.
#pragma once
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "campaign/store.hpp"
#include "model/dataset.hpp"
#include "model/talc.hpp"
#include "model/talc_controller.hpp"

namespace probeloop::campaign {

struct LiveOptions {
  model::TalcOptions talc;
  double grid_s = 0;             // 0: the plan's cycle period
  bool offsets_applied = false;  // the cycles ran with the issued offsets applied
  bool requested_only = false;   // feed TALC only the cycles it asked for
};

struct LiveProgress {
  int ticks = 0, measurements = 0;         // processed by this call
  std::vector<model::TalcEvent> events;    // new events
};

// One stored measurement as TALC saw it. Scored (Table 6.5) when it has a residual and, with
// the offsets applied, ran with one (the first cycles after the first fit may come before
// the first prediction is issued).
struct LiveMeasurement {
  bool scored(bool offsets_applied) const { return !residual.empty() && (!offsets_applied || offset_applied); }
  int cycle = 0, k = 0;
  double t_s = 0;
  bool taken = true;
  bool offset_applied = false;  // the cycle ran with an issued offset (offsets_applied mode)
  std::string phase_before;
  std::vector<double> measured, uncompensated, predicted, residual;  // predicted/residual empty in the CP
};

class LiveLoop {
 public:
  LiveLoop(CampaignStore& store, const LiveOptions& o);
  ~LiveLoop();

  // Processes every step the stored data allow (one transaction per step). log_pending: a log
  // has a torn last line waiting for its end (a cycle may be starting in it).
  LiveProgress advance(bool finished, bool log_pending = false);

  // Seconds the cycle program should wait at time now before starting its next cycle (0:
  // start now). A final cycle not yet processed is taken into account on a copy of the state.
  double waitSeconds(double now_s) const;
  // The predicted errors (LocationErrors order) in effect at t: the latest prediction that
  // applies at or before t; nullopt before the first.
  std::optional<std::array<double, 7>> compensationAt(double t_s) const;

  // The diagnosis made at the latest model version (which input the models miss, and the
  // command that adds it), "" before the first fit.
  const std::string& latestDiagnosis() const { return diagnosis_; }

  bool started() const;
  model::TalcPhase phase() const;
  const std::vector<std::string>& channels() const { return channels_; }
  bool offsetsApplied() const { return o_.offsets_applied; }
  const std::vector<LiveMeasurement>& measurements() const { return done_measurements_; }

 private:
  struct Measurement {
    int cycle = 0;
    double t_s = 0, first_point_s = 0, last_point_s = 0;
    std::vector<double> values;
  };
  struct Issued {
    int k = 0;
    double applies_s = 0;
    std::array<double, 7> values{};
  };
  void load();
  bool run(bool finished, bool write, LiveProgress* progress, bool log_pending = false);
  void processTick(int k, bool finished, bool write);
  void processMeasurement(const Measurement& m, bool write);
  void maybeCloseCalibration(double step_t, bool at_tick, bool write);
  void recordNew(bool write, double t_s);
  double issuedTime(double tk) const;
  std::optional<double> openCycleFirstPoint(bool& untimed) const;
  void applyInputChanges(bool write);
  void addInput(const std::string& name);
  std::string diagnose() const;

  CampaignStore& store_;
  LiveOptions o_;
  std::vector<std::string> channels_;
  model::InputSeries inputs_;
  std::unique_ptr<model::TalcInputColumns> columns_;
  std::vector<Measurement> meas_;
  std::size_t next_meas_ = 0;
  int last_loaded_cycle_ = 0;
  std::unique_ptr<model::TalcController> tc_;
  double grid_s_ = 0, t0_ = 0, cycle_time_s_ = 0;
  int next_tick_ = 0, last_cp_k_ = -1;
  double last_cp_t_ = 0;
  bool cp_extended_ = false;
  std::vector<Issued> issued_;
  std::vector<LiveMeasurement> done_measurements_;
  std::size_t events_recorded_ = 0;
  int models_recorded_ = 0;
  std::string phase_recorded_;
  struct InputChange {
    std::string input;
    int after_steps = 0;
  };
  std::vector<InputChange> changes_;  // stored; applied at their step count
  std::size_t changes_applied_ = 0;
  std::string diagnosis_;
  // Rebuild: the steps already in the store are replayed without writing.
  int stored_ticks_ = 0;
  std::vector<int> stored_cycles_;
};

std::string liveOptionsJson(const LiveOptions& o);

// `campaign add-input`: asks the live loop to add an input column to its models (taken at its
// next pass). InputError, the store untouched, for a column the inputs stream does not have
// (yet), or one the models already use.
void requestLiveInput(CampaignStore& store, const std::string& name);

}  // namespace probeloop::campaign
