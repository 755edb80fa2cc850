// The virtual machine's clock and thermal state: rotary timing, the heat inputs (C, spindle,
// axes, coolant, constant sources), time steps of the thermal network, the duty's tool
// changes and settling, the inputs CSV's samples and the motion trace. The class:
// sim/virtual_machine_detail.hpp.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "model/effects.hpp"
#include "sim/virtual_machine_detail.hpp"

namespace probeloop::sim::detail {

double VirtualMachine::cRpm(double t) {
  if (off_) return 0;
  if (c_move_rpm_ > 0) return c_move_rpm_;  // a feed move turns C (the test's load)
  if (!dwelling_) return 0;
  const auto& d = tr_.duty;
  if (!d.c_profile.empty()) {
    double v = 0;
    for (const auto& [at, rpm] : d.c_profile)
      if (t >= at) v = rpm;
    return v;
  }
  if (!d.c_levels_rpm.empty()) {
    const auto k = static_cast<std::size_t>(std::floor(t / d.hold_s));
    std::uniform_int_distribution<std::size_t> pick(0, d.c_levels_rpm.size() - 1);
    while (duty_levels_.size() <= k) duty_levels_.push_back(d.c_levels_rpm[pick(duty_rng_)]);
    return duty_levels_[k];
  }
  return 0;
}

bool VirtualMachine::mwfOn(double t) const {
  if (off_) return false;
  bool on = coolant_;
  for (const auto& [at, v] : tr_.duty.mwf_profile)
    if (t >= at) on = v;
  return on;
}

Eigen::VectorXd VirtualMachine::heat(double t) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(net_.size());
  for (const auto& s : tr_.thermal.sources) {
    double v = 0;
    switch (s.input) {
      case HeatInput::CAxisRpm: v = std::fabs(cRpm(t)) * s.gain; break;
      case HeatInput::SpindleRpm: v = std::fabs(spindle_rpm_) * s.gain; break;
      case HeatInput::AxisSpeed: v = path_speed_mm_per_min_ / 1000.0 * s.gain; break;
      case HeatInput::Mwf: v = mwfOn(t) ? s.gain : 0.0; break;
      case HeatInput::Constant: v = off_ ? 0.0 : s.gain; break;
    }
    q(s.node) += v;
  }
  return q;
}

// One row of the motion trace: what the controller commanded, when, from which line.
void VirtualMachine::traceRow(const char* kind, const MachinePosition& to, double feed, double t_start) {
  ++motions_;  // every motion, dwell and tool change ends here
  if (!trace_on_) return;
  trace_ << formatNumber(t_start, 3) << "," << formatNumber(t_ - t_start, 3) << "," << line_ << "," << kind << ","
         << formatNumber(to.xyz_mm.x(), 6) << "," << formatNumber(to.xyz_mm.y(), 6) << ","
         << formatNumber(to.xyz_mm.z(), 6) << "," << (m_.a.present ? formatNumber(to.a_deg, 6) + "," : "")
         << formatNumber(to.b_deg, 6) << "," << formatNumber(to.c_deg, 6)
         << "," << formatNumber(feed, 3) << "," << tool_;
  if (trace_program_) trace_ << "," << std::filesystem::path(program_file_).filename().string();
  trace_ << "\n";
}

// Time passes while X/Y/Z move at this path speed (a heat input, and a column of the
// inputs CSV).
void VirtualMachine::move(double dt, double speed_mm_per_min) {
  path_speed_mm_per_min_ = speed_mm_per_min;
  advance(dt);
  path_speed_mm_per_min_ = 0;
}

void VirtualMachine::advance(double dt) {
  const double rate = tr_.inputs_rate_s;
  while (dt > 1e-12) {
    const double next_sample = static_cast<double>(sample_index_) * rate;
    double h = std::min(dt, tr_.thermal.max_step_s);
    if (next_sample > t_ + 1e-9) h = std::min(h, next_sample - t_);
    // A duty tool change ends the step, so it happens at its own time.
    const bool duty_change_due = dwelling_ && next_duty_change_ >= 0;
    if (duty_change_due) h = std::min(h, std::max(0.0, next_duty_change_ - dwell_clock_));
    if (tr_.thermal.present) net_.advance(h, tr_.thermal.environment.at(t_ + h / 2), heat(t_ + h / 2));
    if (tr_.settling_tau_s > 0) settling_ = model::decayStep(settling_, h, tr_.settling_tau_s);
    t_ += h;
    dt -= h;
    if (dwelling_) dwell_clock_ += h;
    while (duty_change_due && dwell_clock_ >= next_duty_change_ - 1e-9) dutyToolChange();
    if (std::fabs(t_ - next_sample) <= 1e-9 || t_ > next_sample) sample();
  }
}

// Tool changes as a Poisson process on the dwell clock: exponential gaps (mean 1/rate).
double VirtualMachine::drawDutyGap() {
  std::exponential_distribution<double> gap(tr_.duty.tool_changes_per_hour / 3600.0);
  return dwell_clock_ + gap(duty_tc_rng_);
}

// Production work while the program waits: the probe goes to the magazine, another tool
// cuts, and the probe is seated again. One change is counted (the probe's return, the one
// that moves its tip): a new ATC step and a new settling jump. Instantaneous on the
// program's clock (the dwell's length is the program's).
void VirtualMachine::dutyToolChange() {
  next_duty_change_ = drawDutyGap();
  if (tool_ == m_.probe.tool && tr_.atc_repeatability_um > 0)
    for (int k = 0; k < 3; ++k) atc_um_(k) = tr_.atc_repeatability_um * duty_atc_normal_(duty_atc_rng_);
  recordToolChange("duty");
}

// Counted in the inputs CSV's next row; a holder seated in the warm spindle starts a unit
// settling jump. The jumps add: the spindle nose's heat deficit obeys a linear heat
// equation, so the responses to successive cold holders superpose (model/effects.hpp
// `transient`, the same primitive). The empty spindle seats no holder.
void VirtualMachine::recordToolChange(const char* source) {
  ++tool_changes_;
  const bool holder = tool_ != m_.tool_change.empty_tool;
  if (holder && tr_.settling_tau_s > 0) settling_ += 1.0;
  tool_change_log_.push_back({{"time_s", t_}, {"tool", tool_}, {"source", source}});
}

void VirtualMachine::sample() {
  std::ostringstream row;
  row << formatNumber(t_, 3);
  for (std::size_t i = 0; i < tr_.thermal.sensors.size(); ++i) {
    const auto& s = tr_.thermal.sensors[i];
    const double T = s.node < 0 ? tr_.thermal.environment.at(t_) : net_.temperatures_C()(s.node);
    const double noisy = T + sensor_offset_[i] + (s.noise_K > 0 ? s.noise_K * sensor_normal_(sensor_rng_) : 0.0);
    row << "," << formatNumber(noisy, 3);
  }
  row << "," << formatNumber(cRpm(t_), 3) << "," << formatNumber(spindle_rpm_, 3) << ","
      << formatNumber(path_speed_mm_per_min_, 3) << "," << (mwfOn(t_) ? 1 : 0) << "," << tool_changes_;
  if (sample_index_ == 0) inputs_header_ = inputs_.str();
  inputs_ << row.str() << "\n";
  tool_changes_ = 0;
  last_sample_t_ = t_;
  ++sample_index_;
  if (live_) live_->inputSample(t_, inputs_header_, row.str());
}

double VirtualMachine::nodeRise(int node) const {
  return node < 0 || !tr_.thermal.present ? 0.0 : net_.temperatures_C()(node) - T0_;
}

}  // namespace probeloop::sim::detail
