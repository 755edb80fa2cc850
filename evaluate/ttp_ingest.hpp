// Reading the thermal test piece's measurements (seed 004 §7.2) into surface points per
// feature, or dial-gauge readings per facet (docs/thermal-test-piece-evaluation.md §1-§2).
//
// Contract:
// - CMM export (CSV): columns x_mm,y_mm,z_mm (or x,y,z), optionally feature, point,
//   nx,ny,nz; '#' comments. The points are surface points (tip-compensated, as CMM software
//   exports them) in the file's frame. Labels that are all manifest feature ids are used as
//   they are; without labels, or with labels that are none of ours, the points are assigned
//   by the nominal geometry (the file must then be in the part frame); a mix is refused.
// - On-machine (LinuxCNC log / Fanuc DPRNT "PT <cycle> <position> <point> x y z", or the
//   simulator's points CSV time_s,cycle,c_deg,feature,point,x_mm,...; feature "P<position>",
//   "S<position>" or a feature id): stylus-tip centres in machine coordinates. The manifest
//   point (feature by position, then point number) gives the approach and C; surface point =
//   tip + r_tip * approach; then the part frame: undo C about the C axis centre
//   (parts::unturnedByTable: a part angle th shows in the machine at th + s C, s =
//   parts::tableTurnSign, -1 when C+ is clockwise), subtract the part origin.
// - Dial gauge (CSV facet,g_um): each facet's reading relative to the reference facet of its
//   side (seed 004 L2121), positive when the facet lies farther from the C axis than the
//   reference (g = d(t_i) - d(t_0), the form of parts::ttpErrors).
// - Every refusal is an InputError naming the file, the line, the feature and what was
//   expected; nothing is guessed silently.
#pragma once
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "evaluate/input_warnings.hpp"
#include "parts/plan_manifest.hpp"

namespace probeloop::evaluate {

enum class TtpRoute { Cmm, OnMachine, Gauge };
const char* ttpRouteName(TtpRoute r);  // "cmm", "on_machine", "gauge"

// One measured surface point (on the material, not the tip centre).
struct TtpPoint {
  std::string feature;  // manifest feature id
  int point = 0;        // number within the feature (the file's, or the order of appearance)
  int line = 0;         // 1-based line in the input file
  Eigen::Vector3d p_mm = Eigen::Vector3d::Zero();  // CMM: the file's frame; on-machine: part frame by nominal C
};

struct TtpPoints {
  std::string file;
  std::string format;       // cmm, linuxcnc, fanuc, csv
  TtpRoute route = TtpRoute::Cmm;
  std::string assigned_by;  // labels | nominal geometry | manifest positions
  std::vector<TtpPoint> points;
  std::vector<InputWarning> warnings;  // what the exchange file's lenient reader warned about
};

struct TtpGaugeReading {
  std::string facet;
  double g_um = 0;
  int line = 0;
};

struct TtpGaugeReadings {
  std::string file;
  std::vector<TtpGaugeReading> readings;
};

// Format names: cmm | linuxcnc | fanuc | log | csv | gauge | features. Detection: a CSV with the
// feature-actuals columns (evaluate/feature_actuals.hpp) is features, one whose header has
// g_um a gauge file, one with c_deg or time_s the on-machine points CSV, any other CSV a
// CMM export; a file that is not CSV a probe log ("log": LinuxCNC and Fanuc lines parse alike).
std::string detectTtpFormat(const std::string& path, const std::string& text);

// QIF and DMIS exports are read leniently (docs/interop.md#lenient-reading): the reader's
// warnings land in TtpPoints::warnings (file, line, what); strict refuses them instead. A feature
// such a file states with its measured geometry but without points, beside features with points,
// is not used: a warning with its line (strict_refuses false: --strict keeps it), or an
// InputError at that line naming it and why when the piece's evaluation needs its points (the
// thermal test piece's datums and cycle-0 reference features; every stepped-workpiece plane).
TtpPoints readTtpCmmExport(const std::string& path, const std::string& text, const parts::PlanManifest& m, bool strict = false);
// format: csv (the points CSV) or linuxcnc | fanuc | log (a PT log).
TtpPoints readTtpOnMachine(const std::string& path, const std::string& text, const std::string& format,
                           const parts::PlanManifest& m);
TtpGaugeReadings readTtpGauge(const std::string& path, const std::string& text, const parts::PlanManifest& m);

// Nominal-geometry assignment (as CMM software does it): the nearest nominal surface within
// 0.5 mm normal distance, inside the feature's nominal extent + 1 mm. Two candidates whose
// distances differ by less than 0.05 mm are ambiguous (an error naming the line and both
// features); a point that fits no feature is an error naming the line and the nearest
// feature with its distance; when most points fit nothing the file is probably in another
// frame and the error says how to fix it. `lines` are the points' file lines.
struct TtpAssignmentRules {
  double normal_tolerance_mm = 0.5;
  double extent_margin_mm = 1.0;
  double ambiguity_mm = 0.05;
};
std::vector<std::string> assignByNominalGeometry(const std::vector<Eigen::Vector3d>& points_mm,
                                                 const std::vector<int>& lines, const parts::PlanManifest& m,
                                                 const std::string& file, const TtpAssignmentRules& rules = {});

// The part-frame position of a machine-coordinate point measured at C = c_deg (the inverse of
// the placement the planner uses): Rz(-s C) (p - centre) + centre - part origin, with
// parts::turnedByTable / unturnedByTable.
Eigen::Vector3d machineToPart(const parts::PlanManifest& m, const Eigen::Vector3d& p_machine_mm, double c_deg);
Eigen::Vector3d partToMachine(const parts::PlanManifest& m, const Eigen::Vector3d& p_part_mm, double c_deg);
// A direction (no translation) the same way.
Eigen::Vector3d machineToPartDirection(const parts::PlanManifest& m, const Eigen::Vector3d& d, double c_deg);
Eigen::Vector3d partToMachineDirection(const parts::PlanManifest& m, const Eigen::Vector3d& d, double c_deg);

}  // namespace probeloop::evaluate
