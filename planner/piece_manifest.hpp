// What the planners of machined test pieces (thermal_test_piece.hpp, stepped_workpiece.hpp)
// fill alike in the plan manifest and the CMM point plan (docs/formats.md#plan-manifest,
// #cmm-plan-of-a-test-piece): the programs on the planned clock, the machine and probe block,
// each feature's finishing time from its cuts, and the CSV of nominal CMM points.
#pragma once
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "parts/machine.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/workpiece.hpp"
#include "planner/program_walker.hpp"

namespace probeloop::planner {

// One manifest entry per program, in order, with its role, log and planned start / duration.
void setManifestPrograms(parts::PlanManifest& m, const std::vector<NotedProgram>& programs,
                         const std::vector<double>& start_s, const std::vector<double>& duration_s);

// The machine block (name, C axis, table, coordinate resolution) and the probe's tool number
// and tool-change repeatability; the tip radius and the probe's repeatability are the caller's.
void setManifestMachine(parts::PlanManifest& m, const parts::Machine& machine);

// What every machined piece's manifest states alike, in this order: its kind and dialect, the
// programs (setManifestPrograms), the machine (setManifestMachine), the tip radius and the
// probe's repeatability, the part's name, origin and material.
void setManifestPiece(parts::PlanManifest& m, const std::string& kind, parts::Dialect dialect,
                      const std::vector<NotedProgram>& programs, const std::vector<double>& start_s,
                      const std::vector<double>& duration_s, const parts::Machine& machine, double tip_radius_mm,
                      double probe_repeatability_2sigma_um, const std::string& part_name,
                      const Eigen::Vector3d& part_origin_mm, const parts::WorkpieceMaterial& material);

// The features' cut times (setFeatureCutTimes) and one probing cycle: the last program, on the
// planned clock.
void setManifestProbingCycle(parts::PlanManifest& m, const std::vector<double>& start_s,
                             const std::vector<double>& duration_s);

// Each feature finished by cuts: the cycle (or step) of its cuts and the mid-time from the
// first cut's start to the last one's end; features without a cut are left as they are.
void setFeatureCutTimes(parts::PlanManifest& m);

// One nominal CMM point: the surface point and its outward unit normal, part frame.
struct CmmRow {
  std::string feature;
  int point = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::UnitZ();
};
// cmm_points.csv: the comment lines (each written after "# "), the header, a row per point.
std::string cmmPointsCsv(const std::vector<std::string>& comments, const std::vector<CmmRow>& rows);

// The seconds of `a` less those of `b`, kind by kind (one program's share of a session).
WalkTimes operator-(const WalkTimes& a, const WalkTimes& b);

}  // namespace probeloop::planner
