// The CMM that inspects a machined workpiece: planned points (nominal surface point and
// outward normal, workpiece frame at 20 °C) are probed along the normal against the surface
// the machine actually cut (sim::Stock's exact surface) with the CMM's own noise.
//
// Contract: readCmmPoints needs the columns feature,point,x_mm,y_mm,z_mm,nx,ny,nz (normal
// unit length within 1e-6, else InputError with file:line). measureOnCmm throws InputError
// naming the point when no surface lies within ±search_mm of the nominal point. Noise:
// normal along the normal with sigma = MPE(L)/2, MPE = A + L/K, L the point's distance from
// the workpiece datum (a length-dependent per-point model); reported to 0.1 um.
// The room: with cmm.temperature_half_width_K > 0 the part's temperature offset dT is drawn
// uniformly within +-half width (seeded, its own stream, sim/random_streams.hpp), and every
// measured point is scaled about the datum by 1 + alpha dT: a CMM that does not correct the
// part's expansion (the evaluation's budget carries it as seed 004 Eq. 7.6). The drawn dT is
// printed in the export's comment line; with half width 0 nothing is drawn and the export
// is what it always was. measured_mm, when given, receives each point's measured position.
#pragma once
#include <Eigen/Dense>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "interop/cmm_document.hpp"
#include "parts/workpiece.hpp"

namespace probeloop::sim {

class Stock;

struct CmmPoint {
  std::string feature;
  int point = 0;
  int line = 0;
  Eigen::Vector3d nominal_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // outward, away from the material
};

std::vector<CmmPoint> readCmmPoints(const std::string& path);
// A QIF 3.0 plan (interop/qif.hpp readQifPlan) as the CMM's points: each feature's planned
// points in order, numbered from 1, line = the feature nominal's line. Refused before anything
// runs: a point without its Normal (the CMM approaches along it), a feature other than a plane,
// sphere or cylinder, one without its nominal geometry, or whose name cannot be a DMIS label.
std::vector<CmmPoint> cmmPointsOfQifPlan(const interop::CmmDocument& plan);  // a DMIS program's too

// alpha_per_K: the part's real expansion coefficient (NaN: the workpiece material's).
std::string measureOnCmm(const Stock& stock, const parts::Workpiece& w, const std::vector<CmmPoint>& points,
                         const std::string& points_file, std::uint64_t seed,
                         double alpha_per_K = std::numeric_limits<double>::quiet_NaN(), double search_mm = 5.0,
                         std::vector<Eigen::Vector3d>* measured_mm = nullptr);

// The CMM's results for a QIF plan or a DMIS program: the plan's features (nominals kept) with their
// measured points (in the plan's order, the plan's outward normals) and the least-squares
// geometry of each (plane, sphere, cylinder; its form = the fit's range of residuals), as
// CMM software reports them; a cylinder probed in one section gets its circle's (centre on the
// axis, the circle's normal as the axis). A feature whose points fix no element keeps its
// points without geometry.
// A program's moves (a DMIS program's GOTO and PTMEAS, plan.moves) against the part as cut,
// the stylus tip as a point (its shaft and the probe body are not modelled): a move that enters
// material, or a probing move that meets it more than 0.5 mm before its point, is an InputError
// naming the program's line, before anything is measured; after a probing move the tip is back
// where that move started. No moves (a QIF plan, a CSV): nothing
// to check; the first move is where the CMM starts.
void checkCmmMoves(const Stock& stock, const interop::CmmDocument& plan);

// cmmResultsDocument: the same as a document, for the QIF and the DMIS writers.
interop::CmmDocument cmmResultsDocument(const interop::CmmDocument& plan, const std::vector<Eigen::Vector3d>& measured_mm);

}  // namespace probeloop::sim
