// Reading probed points from any of the three inputs into one list of records.
//
// A points CSV may come from any probing cycle (docs/formats.md#points-csv): its points in any
// order and number, with the manifest's feature ids, foreign labels or none. A point whose label
// is a manifest id takes that position (its c_deg must agree) and, with a `point` column, that
// planned point. Any other point takes the position planned at its c_deg and not named by an id
// in its cycle; positions that share a C angle (repeats: the same sphere in the same place) need
// a label per position and time_s (the label seen first is the earlier position). A point without
// a planned number must lie within 5 mm of its position's nominal sphere (radius + tip radius
// from the nominal centre) and is paired with its nearest planned contact, for its planned time.
//
// Contract: every record names its source line; a line that cannot belong to the manifest
// (a C angle not planned, a point that fits no position, a trusted point far from its planned
// probing line or twice) is an InputError with file:line. Nothing is guessed silently.
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
  std::optional<double> time_s;  // the CSV's time_s, or the Fanuc log's clock (to the second)
  // The point number is the nearest planned contact's (a point of another cycle's numbering, or
  // none), not the file's: several records may share it.
  bool nearest_point = false;
};

std::vector<ProbeRecord> readProbeRecords(const std::string& path, PointsFormat format,
                                          const parts::PlanManifest& manifest);

// The two steps of readProbeRecords, for a reader that receives a log in pieces (the campaign
// store): the records of a probe log's text (LinuxCNC LOG or Fanuc DPRNT; `first_line` is the
// file line of the text's first line, `session_start_s` as gcode::parseProbeLog), and the check that every record belongs to the plan
// (cycle, position and point planned, none twice among `records`, each within 10 mm of its
// planned contact: farther means a log of another plan). InputError with file:line.
std::vector<ProbeRecord> probeLogRecords(const std::string& text, const std::string& file, int first_line = 1,
                                         std::optional<double>* session_start_s = nullptr);
void checkRecordsBelongToPlan(const std::vector<ProbeRecord>& records, const parts::PlanManifest& manifest,
                              const std::string& file);

// A user's file of cycle start times (`evaluate --cycle-starts`): CSV `cycle,start_s` (the
// separators and decimal marks of core/csv.hpp), the cycles 1, 2, … N in order, each once, the
// starts strictly increasing, N at most the plan's cycles. They replace the plan's schedule
// (manifest.cycle_start_s) for those cycles; cycles after N get NaN, so that a point of theirs
// without its own time is refused by the evaluation rather than stamped from the plan. A point
// that carries its own time (a points CSV's time_s, a Fanuc log's clock) keeps it.
// InputError with file:line:field otherwise.
void applyCycleStarts(parts::PlanManifest& manifest, const std::string& path);

}  // namespace probeloop::evaluate
