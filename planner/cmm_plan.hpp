// The CMM point plan as a QIF 3.0 Plan (interop/qif.hpp) and as a DMIS program (interop/dmis.hpp): each measured feature of the
// manifest with its nominal geometry (part frame) and its planned points (surface point and
// outward normal), for CMM software that reads QIF instead of our cmm_points.csv. The sphere
// artifact's on-machine probing plan the same way: each C position's sphere (machine frame at
// that C) with its contact points on the sphere's surface (tip centre + r_tip x approach) and
// their outward normals (-approach).
//
// Contract: qifCmmPlan reads the cmm_points.csv text the planner wrote (features in order of
// appearance); a feature of the CSV missing from the manifest, or of a kind QIF is not written
// for, is a logic_error (the planner wrote both).
#pragma once
#include <string>

#include "parts/plan_manifest.hpp"

namespace probeloop::planner {

inline constexpr const char* kQifCmmPlanFile = "cmm_plan.qif";
inline constexpr const char* kDmisCmmPlanFile = "cmm_plan.dmi";
inline constexpr const char* kQifProbePlanFile = "probe_plan.qif";

std::string qifCmmPlan(const parts::PlanManifest& m, const std::string& cmm_points_csv);
// The same plan as a DMIS program (interop/dmis.hpp: the moves vertical or at a clearance height).
std::string dmisCmmPlan(const parts::PlanManifest& m, const std::string& cmm_points_csv);
std::string qifSphereProbePlan(const parts::PlanManifest& m);

}  // namespace probeloop::planner
