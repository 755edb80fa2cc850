// The live loop wired to the virtual machine (issue 30 item 4): a sim::LiveLink that writes the
// controller's log and the inputs to files as the machine produces them, ingests them into
// the campaign store and runs the live TALC loop (campaign/live_loop.hpp), answers the axis
// offsets in effect (geometry/compensation_offsets.hpp: seed 004 Eqs. 6.3-6.5 at the tip and B,
// from the prediction issued last) and the seconds the cycle program must wait (Fanuc #500,
// LinuxCNC analog input 0: what `campaign run --controller-file` gives a real controller).
//
// When it syncs: after every inputs sample and after every log line that completes a cycle
// (all its planned points in); the log is written whole lines at a time, so no step waits for
// a torn line. The store runs with synchronous = OFF here: a simulated campaign is rerun, not
// recovered (docs/reliability.md#campaign-store).
#pragma once
#include <fstream>
#include <string>

#include "campaign/live_loop.hpp"
#include "campaign/store.hpp"
#include "parts/machine_offsets.hpp"
#include "sim/live_link.hpp"

namespace probeloop::campaign {

class StoreLiveLink : public sim::LiveLink {
 public:
  // folder: where the growing log and inputs files are written (created; files truncated).
  // machine: the machine the programs run on; on a B/C trunnion with its B line located the
  // offsets turn with B (parts/machine_offsets.hpp); without it, offsets at B = 0 only.
  StoreLiveLink(CampaignStore& store, LiveLoop& loop, const std::string& folder,
                const parts::Machine* machine = nullptr);

  void logLine(double t_s, const std::string& log_name, const std::string& line) override;
  void inputSample(double t_s, const std::string& header, const std::string& row) override;
  Eigen::Vector3d offsetsUm(double t_s, const Eigen::Vector3d& tip_mm, double b_deg) override;
  std::optional<double> externalVariable(double t_s, int n) override;
  double analogInput(double t_s, int n) override;

  int syncs() const { return syncs_; }
  // The run is over: the log is complete (its last cycle final), the loop runs to the end.
  void finish();
  static constexpr int kWaitVariable = 500;  // Fanuc common variable with the seconds to wait
  static constexpr int kWaitAnalogInput = 0;  // LinuxCNC motion.analog-in-00 (M66 E0 L0 -> #5399)

 private:
  void sync();
  CampaignStore& store_;
  LiveLoop& loop_;
  std::string folder_, log_path_, inputs_path_;
  std::ofstream log_, inputs_;
  parts::MachineOffsetFrame frame_;
  int points_per_cycle_ = 0, points_ = 0, cycle_ = 0, syncs_ = 0;
};

}  // namespace probeloop::campaign
