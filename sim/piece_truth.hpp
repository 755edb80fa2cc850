// The truth of a machined test piece (docs/simulator.md §3.1): what a perfect, noise-free CMM
// at 20 °C finds on the surfaces as they were cut, and the errors the evaluation should find
// from them. The evaluation of the CMM export and of the on-machine probing is compared with
// this (within its U).
//
// Contract (thermal test piece, seed 004 §7.2):
// - per plane or cylinder feature of the piece: the exact stock surface (Stock line queries
//   from 0.5 mm outside the nominal surface along the nominal outward normal) sampled on a
//   fixed grid within 80 % of the nominal half extents (planes: at least 5 x 3 points, at
//   most 10 mm apart; the cylinder: 36 points around its mid height); points more than
//   0.02 mm from the feature's median height are other surfaces (the mark, a notch floor)
//   and dropped; a least-squares plane / circle (geometry::fitElement) through the rest;
// - the cut that made it: the swept volume bounding most of its points (a cuts.json index,
//   -1 = the blank), with the machine's state when that cut started;
// - the datum frame as the thesis defines it (seed 004 L2055): Z = the TOP plane's normal,
//   origin = the CYL circle's centre projected onto the TOP plane, Y along the flanks'
//   normals (n_FLANK_N - n_FLANK_P made perpendicular to Z), X = Y x Z;
// - in that frame: facets d = n . (p - O) (along their own normal), Z paths the depth below
//   the datum plane at (0, y_j) and beta = atan2(n_x, n_z) (urad);
// - per cutting cycle (parts::cuttingCycles): parts::TtpMeasures of its Z path and four
//   facets, and parts::ttpErrors against cycle 0; its time is the mean start time of the
//   cuts that made its five surfaces.
//
// Why the datum frame, d, d_Z and beta are built here again rather than taken from evaluate/:
// this is what the evaluation is checked against, so it must not share the evaluation's code
// (an error there would then be on both sides and the comparison would pass); sim/ does not
// depend on evaluate/ either. Only parts::ttpErrors, the thesis's formulas (Eqs. 7.1-7.5,
// 7.9), is shared, and parts/thermal_test_piece_test.cpp checks it against hand derivations.
// The fits themselves are geometry::fitElement, the library's least squares.
#pragma once
#include <Eigen/Dense>
#include <array>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "parts/piece_kinds.hpp"
#include "parts/thermal_test_piece.hpp"
#include "sim/material_removal.hpp"

namespace probeloop::sim {

// The machine when a cutting move started (one per cuts.json entry).
struct CutState {
  double time_s = 0;
  int tool = 0;
  std::array<double, 7> location{};                   // EX0C_um ... EC0C_urad
  Eigen::Vector3d tool_um = Eigen::Vector3d::Zero();  // tool-side translation
  double part_above_20C_K = 0;  // the part's temperature above 20 °C (its expansion, and its support's)
  // Line cuts: the tool pushed away from the material (workpiece frame, um; seed 000
  // Eq. 3.16 + structure), and the linear axes' tool-side error at the cut's start and end.
  Eigen::Vector3d deflection_um = Eigen::Vector3d::Zero();
  Eigen::Vector3d axes_start_um = Eigen::Vector3d::Zero(), axes_end_um = Eigen::Vector3d::Zero();
  double feed_mm_per_min = 0, spindle_rpm = 0;
  // The axes' scale errors from the thermal nodes (and a static EXX_um_per_mm …) at the cut:
  // the thermal position error e_pt of seed 000 is this times the travel (um per mm).
  Eigen::Vector3d scale_um_per_mm = Eigen::Vector3d::Zero();
  // The drives' speed-dependent lost motion held at the cut (tool side, um): what the last
  // moves of each axis left (MachineTruth::lost_motion_um_per_m_per_min).
  Eigen::Vector3d lost_motion_um = Eigen::Vector3d::Zero();
};

struct AsCutFeature {
  std::string id, kind, role;
  bool found = false;
  std::string why;   // when not found
  int points = 0;    // surface points fitted
  // Planes: the foot of the centroid and the outward unit normal; cylinders: the circle at
  // its mid height (centre, radius). Part frame, 20 °C, mm.
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::Zero();
  double radius_mm = 0;
  int cut = -1;  // cuts.json index of the cut that made most of its points; -1 = the blank
  // In the datum frame: facets d; Z paths depth and beta.
  double d_mm = std::numeric_limits<double>::quiet_NaN();
  double depth_mm = std::numeric_limits<double>::quiet_NaN();
  double beta_urad = std::numeric_limits<double>::quiet_NaN();
};

struct DatumFrame {
  bool found = false;
  std::string why;
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
};

struct TtpCycleTruth {
  int cycle = 0, z_path = 0, facet = 0;
  bool complete = false;
  std::string why;
  double time_s = std::numeric_limits<double>::quiet_NaN();
  parts::TtpMeasures measures;
  parts::TtpErrors errors;
};

struct TestPieceTruth {
  std::vector<AsCutFeature> features;
  DatumFrame datum;
  std::vector<TtpCycleTruth> cycles;
  std::vector<CutState> cuts;
};

TestPieceTruth testPieceTruth(const parts::TestPiece& piece, const Stock& stock, const std::vector<CutState>& cuts);

// Adds "features", "datum_frame" and "ttp_cycles" to truth.json.
void writeTestPieceTruth(const TestPieceTruth& t, nlohmann::ordered_json& truth);

// Any other machined test piece (the stepped workpiece, seed 000): every feature as cut
// (the sampling and fit above) with the machine's state, deflection and axis errors of the
// cut that made it; truth.json gets "features" (no datum frame, no cycles).
std::vector<AsCutFeature> asCutFeatures(const parts::TestPiece& piece, const Stock& stock);
void writeAsCutFeatures(const std::vector<AsCutFeature>& features, const std::vector<CutState>& cuts,
                        nlohmann::ordered_json& truth);

}  // namespace probeloop::sim
