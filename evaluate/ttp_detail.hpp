// Internal to the thermal-test-piece evaluation (thermal_test_piece.hpp is the public contract):
// what its files share. The steps in the order a reader follows them (evaluateImpl in
// thermal_test_piece.cpp calls them in this order):
//   points grouped by feature (thermal_test_piece.cpp) -> datum frame (ttp_frame.cpp) ->
//   scatter per point (ttp_budget.cpp) -> alignment report (ttp_frame.cpp) -> one LS plane per
//   Z path and facet (ttp_fits.cpp) -> pooled type A scatter (ttp_budget.cpp) -> d, d_Z, beta
//   per feature (ttp_fits.cpp) -> frame sensitivities (ttp_frame.cpp) -> E_X ... E_TTP and dT
//   per cycle (ttp_values.cpp) with their budgets (ttp_budget.cpp) -> spans (ttp_spans.cpp).
// The dial-gauge route (ttp_gauge.cpp) and the planner's prediction (ttp_prediction.cpp) reuse
// the cycle and budget pieces.
#pragma once
#include <Eigen/Dense>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "evaluate/thermal_test_piece.hpp"
#include "geometry/elements.hpp"
#include "parts/plan_manifest.hpp"
#include "uncertainty/budget.hpp"

namespace probeloop::evaluate::ttp {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using uncertainty::Contribution;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

inline constexpr double kInf = std::numeric_limits<double>::infinity();

inline std::string num(double v) { return formatSignificant4(v); }

// --- points ---------------------------------------------------------------------------

struct Pt {
  std::string feature;
  int line = 0;
  Vector3d file_mm, part_mm;
  double sigma_b_mm = 0;    // specification scatter along the normal
  double sigma_res_mm = 0;  // coordinate resolution along the normal (on-machine)
};

// Point indices per feature id, in file order.
using PointsByFeature = std::map<std::string, std::vector<int>>;

// InputError naming the file, the feature, its point count and its lines (thermal_test_piece.cpp).
[[noreturn]] void featureError(const std::string& file, const std::vector<Pt>& all, const std::vector<int>& idx,
                               const std::string& id, const std::string& what);

// --- planes with what the budget needs -------------------------------------------------

struct PlaneModel {
  Vector3d c = Vector3d::Zero(), n = Vector3d::UnitZ();  // n oriented like the nominal direction
  Matrix6d C = Matrix6d::Zero();                         // (J^T J)^-1 in (c, n) order, oriented
  std::vector<int> pts;                                  // indices into the point list
  std::vector<Vector6d> infl;                            // d(c, n) / d(normal displacement of point k)
  double rms_mm = 0, ssr_mm2 = 0, form_ls_mm = 0, form_mz_mm = -1;
  int dof = 0;
};

// --- the datum frame (ttp_frame.cpp) -------------------------------------------------------

struct DatumSets {
  std::vector<Vector3d> top, flank_p, flank_n, cyl;
};

struct FrameFits {
  TtpFrame frame;
  geometry::FitResult top, flank_p, flank_n, cyl;  // cyl: circle2d in the datum plane's coordinates
};

// A datum whose points do not determine its element.
struct DatumFailure : GeometryError {
  std::string id;
  DatumFailure(std::string datum, const std::string& what) : GeometryError(what), id(std::move(datum)) {}
};

FrameFits buildFrame(const DatumSets& d);

// The datums' points (file frame) and their fits, the part frame among them.
struct DatumFits {
  DatumSets sets;
  FrameFits fits;
};

// Datum frame: the datum points of the file, checked (>= 3 each), and the frame built from them;
// InputError naming the datum otherwise.
DatumFits fitDatums(const std::string& file, const std::vector<Pt>& pts, const PointsByFeature& by);
// Alignment report: the file -> part transform and each datum's point count and form.
TtpAlignment alignmentReport(const DatumSets& ds, const FrameFits& ff, bool form_mz);
// Frame sensitivities to every datum point (central differences of the construction): index of
// the point and d(dO, omega) / d(normal displacement).
std::vector<std::pair<int, Vector6d>> datumSensitivities(const DatumSets& ds, const FrameFits& ff, const PointsByFeature& by);

// --- measured quantities and their sensitivities ------------------------------------------

struct FQ {  // one quantity of one fitted feature
  const TtpFeatureResult* feature = nullptr;
  double value = 0;          // mm (D, DZ) or urad (Beta)
  std::vector<int> pts;      // point indices
  std::vector<double> s;     // d value / d(normal displacement of the point), per mm
  Vector6d frame = Vector6d::Zero();  // d value / d(dO, omega)
  double shift = 0;          // d value / d(rigid shift of the feature along its normal)
  double length_mm = 0;      // for the part temperature (on-machine)
};

// d of the facets (dq), d_Z (zq) and beta (bq) of the Z paths, by feature id.
struct FeatureQuantities {
  std::map<std::string, FQ> dq, zq, bq;
};

// --- fits (ttp_fits.cpp) ---------------------------------------------------------------------

// Measurement features: one LS plane each (part frame), checked against its nominal one; the
// results appended to `features`, the planes returned by feature id.
std::map<std::string, PlaneModel> fitFeatures(const parts::PlanManifest& m, const std::string& file, const std::vector<Pt>& pts,
                                              const PointsByFeature& by, const std::map<int, double>& times, bool form_mz,
                                              std::vector<TtpFeatureResult>& features);
// Quantities per feature: d, d_Z, beta with their sensitivities, and each feature's d_mm,
// depth_mm, beta_urad and u_d_um. The FQs point into `features`.
FeatureQuantities featureQuantities(const parts::PlanManifest& m, const std::map<std::string, PlaneModel>& planes,
                                    const std::vector<Pt>& pts, const TtpScatter& scatter,
                                    std::vector<TtpFeatureResult>& features);

// --- values and budgets (ttp_values.cpp, ttp_budget.cpp) -------------------------------------

// A value E = unit * sum_k w_k (q_k(cycle i) - q_k(cycle 0)).
struct Pair {
  const FQ* at_i;
  const FQ* at_0;
  double w;
};

struct ValueSpec {
  std::string quantity, unit;
  double value = 0;
  std::vector<Pair> pairs;
  double unit_factor = 1e3;  // mm -> um; 1 for urad
  bool angle = false;
};

struct BudgetContext {
  const parts::PlanManifest* m = nullptr;
  TtpRoute route = TtpRoute::Cmm;
  const std::vector<Pt>* pts = nullptr;
  TtpScatter scatter;
  bool predicted = false;
  double k = 2.0;
  // Datum points: index and d(dO, omega)/d(normal displacement).
  std::vector<std::pair<int, Vector6d>> datum_sens;
  bool stated = false;  // the features route: the points placed on the file's features
};

// Scatter per point: sigma_b_mm (CMM: MPE(L)/2; on-machine: sigma_spec_om) and, on the machine,
// sigma_res_mm.
void setPointScatter(std::vector<Pt>& pts, const parts::PlanManifest& m, TtpRoute route, double sigma_spec_om);
// Type A: pooled residual of the measurement-feature fits, against the type B specification.
TtpScatter pooledScatter(const std::map<std::string, PlaneModel>& planes, const std::vector<Pt>& pts, double sigma_spec_om,
                         bool predicted);
std::string alphaBasis(const parts::PlanManifest& m);
uncertainty::Budget valueBudget(const ValueSpec& v, const BudgetContext& ctx);
// Eq. 7.10 with its budget from the budget of E_TTP in the radial form (Eq. 7.9).
uncertainty::Budget temperatureBudget(const parts::PlanManifest& m, const uncertainty::Budget& ettp_7_9, double k,
                                      bool predicted);
uncertainty::Budget zeroBudget(const std::string& q, const std::string& unit, double k);

// --- cycles (ttp_values.cpp) ---------------------------------------------------------------------

std::map<int, std::string> phases(const parts::PlanManifest& m);
// Cycle times: the mean planned cut time of the cycle's features.
std::map<int, double> cycleTimes(const parts::PlanManifest& m);

// The manifest's measurement features per cycle and side.
struct CycleFeatures {
  std::map<std::string, const parts::ManifestFeature*> by_side;  // Z, X1, X2, Y1, Y2
};
std::map<int, CycleFeatures> cycleFeatures(const parts::PlanManifest& m);

inline constexpr const char* kSides[4] = {"X1", "X2", "Y1", "Y2"};

// One line per cycle: the values left out and the features that are absent.
std::string missingMessage(const std::map<std::string, bool>& ok, const std::vector<std::string>& absent, int cycle,
                           const std::string& why);

// The manifest's rules (parts::thermalTestPieceEvaluation), for the gauge route those of the
// values it gives.
std::vector<parts::EvaluationRule> formulas(const parts::PlanManifest& m, TtpRoute route);

// A cycle's row before its values: its phase (cycle 0: the reference) and time.
template <class Phases, class Times>
TtpCycleResult cycleResult(int c, const Phases& ph, const Times& times) {
  TtpCycleResult cr;
  cr.cycle = c;
  cr.phase = ph.count(c) ? ph.at(c) : (c == 0 ? "reference" : "");
  cr.time_s = times.count(c) ? times.at(c) : 0.0;
  return cr;
}

inline constexpr const char* kQuantities[6] = {"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um", "dT_K"};
inline constexpr const char* kUnits[6] = {"um", "um", "um", "urad", "um", "K"};

// Cycles: cycle 0 (zeros) first, then every measurement cycle's E_X ... E_TTP and dT (seed 004
// Eqs. 7.1-7.5, 7.9, 7.10) against the reference cut, each with its budget unless
// !opt.budgets. InputError for a missing reference feature.
std::vector<TtpCycleResult> cycleValues(const parts::PlanManifest& m, const std::string& file, const TtpOptions& opt,
                                        bool predicted, const std::map<int, double>& times,
                                        const std::map<std::string, PlaneModel>& planes, FeatureQuantities& fq,
                                        const BudgetContext& ctx);

// --- the evaluation (thermal_test_piece.cpp) ---------------------------------------------------

// The features route (ttp_features.cpp): per manifest feature, what the file states about the
// scatter of its points (evaluate/feature_points.hpp). NaN: not stated.
struct StatedSigma {
  double scale = 1.0;    // StatedScatter::point_scale (>= 1): a placed point stands for that many measured ones
  double form_mm = NAN;  // the form-based sigma of one measured point (sigmaFromForm)
  double dof = 0;        // its degrees of freedom, rangeDof(n) (0: no form)
  double u_mm = NAN;     // the sigma per measured point a stated u of the location implies
};
using StatedSigmas = std::map<std::string, StatedSigma>;
// The stated forms of the Z paths and facets pooled as the point route pools their residuals:
// s^2 = sum(nu_f s_f^2) / sum(nu_f), in TtpScatter's type A fields; used when larger than the
// specification (type_a_used).
TtpScatter statedScatter(const parts::PlanManifest& m, const StatedSigmas& s, double type_b_sigma_mm);
// sigma per placed point: the larger of the pooled form-based s (when used) or the point's
// specification, and the sigma the feature's stated u implies, per measured point, times the
// feature's scale; and which it was ("specification", "stated forms", "stated u").
std::pair<double, const char*> statedPointSigma(double spec_mm, const StatedSigma& s, const TtpScatter& pooled);

// The CMM and on-machine routes; predicted: from the planned points (type B scatter only, the
// terms that scale with measured values listed with 0); stated: the features route (the points
// placed on the file's features; their scatter from statedScatter and statedPointSigma, e.stated's
// sigma per feature filled).
TtpEvaluation evaluateImpl(const parts::PlanManifest& m, const TtpPoints& in, const TtpOptions& opt, bool predicted,
                           const StatedSigmas* stated = nullptr);
// The planned surface points of every probed feature in the part frame (the manifest's contact
// points: the tip centre moved by the tip radius along the approach, C undone).
std::map<std::string, std::vector<Vector3d>> plannedSurfacePoints(const parts::PlanManifest& m);

}  // namespace probeloop::evaluate::ttp
