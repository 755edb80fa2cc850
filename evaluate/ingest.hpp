// Reading probed points from any of the three inputs into one list of records.
// Contract: every record names its source line; a line that cannot belong to the manifest
// (unknown position or point, a point far from its planned probing line, a duplicate) is an
// InputError with file:line. Nothing is guessed silently.
#pragma once
#include <Eigen/Dense>
#include <optional>
#include <string>
#include <vector>

#include "parts/plan_manifest.hpp"

namespace probeloop::evaluate {

enum class PointsFormat { Auto, LinuxCncLog, FanucDprnt, PointsCsv };
PointsFormat parsePointsFormat(const std::string& name);  // auto|linuxcnc|fanuc|csv

struct ProbeRecord {
  std::string file;
  int line = 0;
  int cycle = 0, position = 0, point = 0;
  Eigen::Vector3d tip_mm = Eigen::Vector3d::Zero();
  std::optional<double> time_s;  // only the CSV carries times
};

std::vector<ProbeRecord> readProbeRecords(const std::string& path, PointsFormat format,
                                          const parts::PlanManifest& manifest);

}  // namespace probeloop::evaluate
