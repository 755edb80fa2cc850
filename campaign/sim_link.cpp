#include "campaign/sim_link.hpp"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "core/error.hpp"
#include "geometry/location_errors.hpp"

namespace probeloop::campaign {

StoreLiveLink::StoreLiveLink(CampaignStore& store, LiveLoop& loop, const std::string& folder,
                             const parts::Machine* machine)
    : store_(store), loop_(loop), folder_(folder) {
  std::filesystem::create_directories(folder);
  inputs_path_ = (std::filesystem::path(folder) / "inputs.csv").string();
  inputs_.open(inputs_path_, std::ios::trunc);
  if (!inputs_) throw InputError(inputs_path_, 0, "cannot write the live inputs file");
  const auto& m = store.manifest();
  const double pivot_z = m.table_surface_z_mm + (std::isfinite(m.sphere_centre_height_mm) ? m.sphere_centre_height_mm : 0.0);
  if (machine) frame_ = parts::machineOffsetFrame(*machine, pivot_z, m.radius_from_axis_mm);
  // The C axis, the pivot and d/2 as the plan measured them (the manifest).
  frame_.frame.table.axis_centre_xy_mm = m.c_axis_centre_mm;
  frame_.frame.table.pivot_z_mm = pivot_z;
  frame_.frame.table.reference_radius_mm = m.radius_from_axis_mm;
  points_per_cycle_ = static_cast<int>(m.spheres.size()) * m.pointsPerSphere();
  store.database().exec("PRAGMA synchronous = OFF");
}

void StoreLiveLink::logLine(double /*t_s*/, const std::string& log_name, const std::string& line) {
  if (!log_.is_open()) {
    log_path_ = (std::filesystem::path(folder_) / (log_name.empty() ? "controller.log" : log_name)).string();
    log_.open(log_path_, std::ios::trunc);
    if (!log_) throw InputError(log_path_, 0, "cannot write the live log file");
  }
  log_ << line << "\n";
  log_.flush();
  // A cycle's last planned point completes it: the store can evaluate it now.
  if (line.rfind("PT", 0) != 0) return;
  std::istringstream in(line.substr(2));
  int cycle = 0;
  in >> cycle;
  if (cycle != cycle_) {
    cycle_ = cycle;
    points_ = 0;
  }
  if (++points_ == points_per_cycle_) sync();
}

void StoreLiveLink::inputSample(double /*t_s*/, const std::string& header, const std::string& row) {
  if (inputs_.tellp() == 0) inputs_ << header;
  inputs_ << row << "\n";
  inputs_.flush();
  sync();
}

void StoreLiveLink::sync() {
  ++syncs_;
  store_.ingestInputs(inputs_path_);
  if (log_.is_open()) store_.ingestLog(log_path_, false);
  loop_.advance(false, false);
}

void StoreLiveLink::finish() {
  store_.ingestInputs(inputs_path_);
  if (log_.is_open()) store_.ingestLog(log_path_, true);
  loop_.advance(true, false);
}

Eigen::Vector3d StoreLiveLink::offsetsUm(double t_s, const Eigen::Vector3d& tip_mm, double b_deg) {
  const auto c = loop_.compensationAt(t_s);
  if (!c) return Eigen::Vector3d::Zero();
  const auto o = frame_.offsetsAt(geometry::LocationErrors::fromValues(*c), tip_mm, b_deg);
  return {o.x_um, o.y_um, o.z_um};
}

std::optional<double> StoreLiveLink::externalVariable(double t_s, int n) {
  if (n != kWaitVariable) return std::nullopt;
  return std::round(loop_.waitSeconds(t_s));
}

double StoreLiveLink::analogInput(double t_s, int n) { return n == kWaitAnalogInput ? std::round(loop_.waitSeconds(t_s)) : 0.0; }

}  // namespace probeloop::campaign
