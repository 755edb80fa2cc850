// Evaluation of the thermal test piece (contract in thermal_test_piece.hpp; the definitions and
// every budget term with its derivation in docs/thermal-test-piece-evaluation.md).
#include "evaluate/thermal_test_piece.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "geometry/fit.hpp"
#include "geometry/least_squares.hpp"
#include "geometry/minimum_zone.hpp"
#include "parts/thermal_test_piece.hpp"

namespace probeloop::evaluate {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using uncertainty::Contribution;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

const uncertainty::Budget* TtpCycleResult::value(const std::string& q) const {
  for (const auto& b : values)
    if (b.quantity == q) return &b;
  return nullptr;
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Central-difference step of the datum construction (mm): the frame is smooth in the points,
// second-order terms at 1 um are ~1e-8 relative.
constexpr double kFrameStepMm = 1e-3;

std::string num(double v) { return formatSignificant4(v); }

std::string lineList(const std::vector<int>& lines) {
  std::string s;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (i == 12) return s + ", ...";
    s += (i ? ", " : "") + std::to_string(lines[i]);
  }
  return s;
}

// --- points ---------------------------------------------------------------------------

struct Pt {
  std::string feature;
  int line = 0;
  Vector3d file_mm, part_mm;
  double sigma_b_mm = 0;    // specification scatter along the normal
  double sigma_res_mm = 0;  // coordinate resolution along the normal (on-machine)
};

// --- planes with what the budget needs -------------------------------------------------

struct PlaneModel {
  Vector3d c = Vector3d::Zero(), n = Vector3d::UnitZ();  // n oriented like the nominal direction
  Matrix6d C = Matrix6d::Zero();                         // (J^T J)^-1 in (c, n) order, oriented
  std::vector<int> pts;                                  // indices into the point list
  std::vector<Vector6d> infl;                            // d(c, n) / d(normal displacement of point k)
  double rms_mm = 0, ssr_mm2 = 0, form_ls_mm = 0, form_mz_mm = -1;
  int dof = 0;
};

[[noreturn]] void featureError(const std::string& file, const std::vector<Pt>& all, const std::vector<int>& idx,
                               const std::string& id, const std::string& what) {
  std::vector<int> lines;
  for (int i : idx) lines.push_back(all[static_cast<std::size_t>(i)].line);
  throw InputError(file, lines.empty() ? 0 : lines.front(),
                   "feature " + id + " has " + std::to_string(idx.size()) + " point" + (idx.size() == 1 ? "" : "s") +
                       (lines.empty() ? "" : " (lines " + lineList(lines) + ")") + ": " + what);
}

PlaneModel fitPlaneModel(const std::vector<Vector3d>& pts, const std::vector<int>& idx, const Vector3d& nominal_dir,
                         bool mz) {
  geometry::FitOptions fo;  // least squares
  const auto ef = geometry::fitElement(geometry::ElementKind::Plane, pts, fo);
  const auto& fr = ef.fit;
  PlaneModel p;
  p.c = fr.element.position_mm;
  p.n = fr.element.direction.normalized();
  p.C = fr.covariance_unscaled;
  if (p.n.dot(nominal_dir) < 0) {
    p.n = -p.n;
    Vector6d s;
    s << 1, 1, 1, -1, -1, -1;
    p.C = s.asDiagonal() * p.C * s.asDiagonal();
  }
  p.pts = idx;
  for (const auto& q : pts) {
    // Residual r = n.(q - c): dr/dc = -n, dr/dn = q - c. A displacement eps of the point along
    // n changes its residual by eps; least squares moves the parameters by -C J^T eps.
    Vector6d J;
    J << -p.n, q - p.c;
    p.infl.push_back(-p.C * J);
  }
  p.rms_mm = fr.rms_mm;
  p.ssr_mm2 = fr.ssr_mm2;
  p.dof = fr.dof;
  p.form_ls_mm = fr.form_mm;
  if (mz) {
    try {
      p.form_mz_mm = geometry::fitMinimumZone(geometry::ElementKind::Plane, pts).form_mm;
    } catch (const GeometryError&) {
      p.form_mz_mm = fr.form_mm;  // degenerate for the zone search: the LS peak to valley
    }
  }
  return p;
}

// --- the datum frame ---------------------------------------------------------------------

struct DatumSets {
  std::vector<Vector3d> top, flank_p, flank_n, cyl;
};

struct FrameFits {
  TtpFrame frame;
  geometry::FitResult top, flank_p, flank_n, cyl;  // cyl: circle2d in the datum plane's coordinates
};

std::vector<Vector3d>& datumSet(DatumSets& d, const std::string& id) {
  if (id == "TOP") return d.top;
  if (id == "FLANK_P") return d.flank_p;
  if (id == "FLANK_N") return d.flank_n;
  return d.cyl;
}

Vector3d centroid(const std::vector<Vector3d>& v) {
  Vector3d s = Vector3d::Zero();
  for (const auto& p : v) s += p;
  return s / static_cast<double>(v.size());
}

// seed 004 L2055: TOP -> z and its origin; the flanks' symmetry -> x direction; the LS circle
// of CYL -> the x/y origin.
// A datum whose points do not determine its element.
struct DatumFailure : GeometryError {
  std::string id;
  DatumFailure(std::string datum, const std::string& what) : GeometryError(what), id(std::move(datum)) {}
};

geometry::FitResult fitDatum(const std::string& id, geometry::ElementKind kind, const geometry::Points3& pts) {
  try {
    return geometry::fitLeastSquares(kind, pts);
  } catch (const GeometryError& e) {
    throw DatumFailure(id, e.what());
  }
}

FrameFits buildFrame(const DatumSets& d) {
  FrameFits f;
  f.top = fitDatum("TOP", geometry::ElementKind::Plane, d.top);
  f.flank_p = fitDatum("FLANK_P", geometry::ElementKind::Plane, d.flank_p);
  f.flank_n = fitDatum("FLANK_N", geometry::ElementKind::Plane, d.flank_n);
  Vector3d z = f.top.element.direction.normalized();
  // Up: the flanks and the datum band lie below the top face.
  std::vector<Vector3d> below = d.flank_p;
  below.insert(below.end(), d.flank_n.begin(), d.flank_n.end());
  below.insert(below.end(), d.cyl.begin(), d.cyl.end());
  if ((centroid(below) - f.top.element.position_mm).dot(z) > 0) z = -z;
  // Each flank's outward normal points into the notch, toward the other flank.
  Vector3d np = f.flank_p.element.direction.normalized(), nn = f.flank_n.element.direction.normalized();
  if ((centroid(d.flank_n) - f.flank_p.element.position_mm).dot(np) < 0) np = -np;
  if ((centroid(d.flank_p) - f.flank_n.element.position_mm).dot(nn) < 0) nn = -nn;
  Vector3d y = nn - np;
  y -= y.dot(z) * z;
  if (!(y.norm() > 1e-9))
    throw GeometryError("the flanks FLANK_P and FLANK_N are parallel to the top plane: no X direction");
  y.normalize();
  const Vector3d x = y.cross(z);
  const Vector3d p0 = f.top.element.position_mm;
  geometry::Points3 q;
  for (const auto& p : d.cyl) q.emplace_back((p - p0).dot(x), (p - p0).dot(y), 0.0);
  f.cyl = fitDatum("CYL", geometry::ElementKind::Circle2D, q);
  f.frame.origin_mm = p0 + f.cyl.element.position_mm.x() * x + f.cyl.element.position_mm.y() * y;
  f.frame.R.row(0) = x.transpose();
  f.frame.R.row(1) = y.transpose();
  f.frame.R.row(2) = z.transpose();
  return f;
}

// Frame change (delta O, omega) in part coordinates between two frames: new part coordinates
// p'' = M (p' - dO) with M = R' R^T ~ I - [omega]x.
Vector6d frameDelta(const TtpFrame& a, const TtpFrame& b) {
  Vector6d xi;
  xi.head<3>() = a.R * (b.origin_mm - a.origin_mm);
  const Matrix3d M = b.R * a.R.transpose();
  xi(3) = (M(1, 2) - M(2, 1)) / 2;
  xi(4) = (M(2, 0) - M(0, 2)) / 2;
  xi(5) = (M(0, 1) - M(1, 0)) / 2;
  return xi;
}

// --- measured quantities and their sensitivities ------------------------------------------

enum class Q { D, DZ, Beta };

struct FQ {  // one quantity of one fitted feature
  const TtpFeatureResult* feature = nullptr;
  double value = 0;          // mm (D, DZ) or urad (Beta)
  std::vector<int> pts;      // point indices
  std::vector<double> s;     // d value / d(normal displacement of the point), per mm
  Vector6d frame = Vector6d::Zero();  // d value / d(dO, omega)
  double shift = 0;          // d value / d(rigid shift of the feature along its normal)
  double length_mm = 0;      // for the part temperature (on-machine)
};

FQ quantity(const TtpFeatureResult& f, const PlaneModel& p, Q q, double y_path) {
  FQ r;
  r.feature = &f;
  r.pts = p.pts;
  const Vector3d& c = p.c;
  const Vector3d& n = p.n;
  Vector6d J = Vector6d::Zero();
  if (q == Q::D) {
    r.value = n.dot(c);  // d = n.(c - O), O = 0 in the part frame
    J << n, c;
    r.frame << -n, Vector3d::Zero();
    r.length_mm = std::fabs(r.value);
  } else if (q == Q::DZ) {
    const double x0 = 0.0;
    const double a = n.x() * (x0 - c.x()) + n.y() * (y_path - c.y());
    const double z_at = c.z() - a / n.z();
    r.value = -z_at;  // depth below the datum plane z = 0
    J << -n.x() / n.z(), -n.y() / n.z(), -1.0, (x0 - c.x()) / n.z(), (y_path - c.y()) / n.z(), -a / (n.z() * n.z());
    const Vector3d P(x0, y_path, z_at);
    r.frame << n / n.z(), P.cross(n) / n.z();
    r.length_mm = std::fabs(r.value);
  } else {
    const double h = n.x() * n.x() + n.z() * n.z();
    r.value = std::atan2(n.x(), n.z()) * 1e6;
    const Vector3d b = Vector3d(n.z(), 0.0, -n.x()) / h * 1e6;
    J << Vector3d::Zero(), b;
    r.frame << Vector3d::Zero(), b.cross(n);
  }
  for (const auto& k : p.infl) r.s.push_back(J.dot(k));
  r.shift = J.head<3>().dot(n);
  return r;
}

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
};

std::string alphaBasis(const parts::PlanManifest& m) {
  return "alpha = " + num(m.material_alpha_um_per_m_K) + " um/(m K) (part.alpha_um_per_m_K, the blank's material)";
}

uncertainty::Budget valueBudget(const ValueSpec& v, const BudgetContext& ctx) {
  const auto& m = *ctx.m;
  const auto& pts = *ctx.pts;
  std::vector<Contribution> cs;
  auto add = [&](std::string input, char type, std::string dist, std::string basis, double u, double dof = kInf) {
    cs.push_back({std::move(input), type, std::move(dist), std::move(basis), u, dof});
  };
  // Per-point gradient (value unit per mm of normal displacement), per-feature shift gradient.
  std::map<int, double> g;
  std::map<const TtpFeatureResult*, double> shift;
  Vector6d G = Vector6d::Zero();
  for (const auto& pr : v.pairs)
    for (int side = 0; side < 2; ++side) {
      const FQ& q = side == 0 ? *pr.at_i : *pr.at_0;
      const double w = (side == 0 ? pr.w : -pr.w) * v.unit_factor;
      for (std::size_t j = 0; j < q.pts.size(); ++j) g[q.pts[j]] += w * q.s[j];
      shift[q.feature] += w * q.shift;
      G += w * q.frame;
    }
  double sb2 = 0, sum_g2 = 0, sres2 = 0;
  for (const auto& [i, gi] : g) {
    const auto& p = pts[static_cast<std::size_t>(i)];
    sb2 += std::pow(p.sigma_b_mm * gi, 2);
    sres2 += std::pow(p.sigma_res_mm * gi, 2);
    sum_g2 += gi * gi;
  }
  const auto& sc = ctx.scatter;
  const bool cmm = ctx.route == TtpRoute::Cmm;
  const std::string both = ", this and the reference cycle";
  const std::string spec_name = cmm ? "CMM probing error (specification)" : "probe repeatability (specification)";
  const std::string spec_basis =
      cmm ? "MPE = " + num(m.ttp.cmm.mpe_constant_um) + " um" +
                (m.ttp.cmm.mpe_length_mm > 0 ? " + L/" + num(m.ttp.cmm.mpe_length_mm) : std::string()) +
                " (thermal_test_piece.cmm; seed 004 L2145), sigma = MPE(L)/2 per point, L = distance from the origin; "
                "through each plane fit's (J^T J)^-1"
          : "probe.repeatability_2sigma = " + num(m.probe_repeatability_2sigma_um) +
                " um: sigma = " + num(m.probe_repeatability_2sigma_um / 2) + " um per point; through each plane fit's (J^T J)^-1";
  const std::string pooled = "pooled residual of the Z-path and facet plane fits: s = " + num(sc.type_a_sigma_mm * 1e3) +
                             " um, nu = " + num(sc.type_a_dof);
  if (sc.type_a_used) {
    add("point scatter (type A)" + both, 'A', "normal", pooled, sc.type_a_sigma_mm * std::sqrt(sum_g2), sc.type_a_dof);
    add(spec_name + both, 'B', "normal", spec_basis + "; not added: the type A estimate of the same scatter is larger", 0);
  } else {
    add(spec_name + both, 'B', "normal", spec_basis, std::sqrt(sb2));
    if (ctx.predicted)
      add("point scatter (type A)" + both, 'A', "normal", "needs measured points (not predicted)", 0);
    else if (sc.type_a_dof > 0)
      add("point scatter (type A)" + both, 'A', "normal", pooled + "; not added: the specification is larger", 0, sc.type_a_dof);
  }
  if (ctx.route == TtpRoute::OnMachine) {
    const double q = m.coordinate_resolution_mm;
    add("coordinate resolution" + both, 'B', "rectangular",
        "q = " + num(q * 1e3) + " um per coordinate (machine.coordinate_resolution), q/sqrt(12) along each point's normal",
        std::sqrt(sres2));
    const double rep = m.ttp.on_machine_repeatability_um / 2 * 1e-3;
    double v2 = 0;
    for (const auto& [f, s] : shift) v2 += s * s;
    add("machine repeatability" + both, 'B', "normal",
        "thermal_test_piece.on_machine.repeatability = " + num(m.ttp.on_machine_repeatability_um) +
            " um (seed 004 L2145: added to the probe's), read as 2 sigma; one rigid shift along the normal per feature "
            "measurement",
        rep * std::sqrt(v2));
  } else {
    add("coordinate resolution" + both, 'B', "rectangular", "part of the CMM's MPE (not added again)", 0);
  }
  // Temperature of the part.
  const double alpha = m.material_alpha_um_per_m_K;
  if (v.angle) {
    add("part temperature", 'B', "rectangular", "a uniform temperature changes no angle", 0);
  } else if (!std::isfinite(alpha)) {
    add("part temperature", 'B', "rectangular", "not stated: set blank.material.alpha_um_per_m_K in the part file", 0);
  } else if (cmm) {
    const double dT = m.ttp.cmm.temperature_half_width_K;
    if (ctx.predicted)
      add("part temperature in the CMM room (Eq. 7.6)", 'B', "rectangular",
          "U_dT = alpha dT |E| (seed 004 Eq. 7.6) read as a rectangular half-width, " + alphaBasis(m) + ", dT within +-" +
              num(dT) + " K: scales with the measured value",
          0);
    else
      add("part temperature in the CMM room (Eq. 7.6)", 'B', "rectangular",
          "U_dT = alpha dT |E| (seed 004 Eq. 7.6, a 'measurement deviation assessment'), read as the half-width of a "
          "rectangular distribution (our interpretation): u = U_dT / sqrt(3); " + alphaBasis(m) + ", dT within +-" + num(dT) +
              " K (thermal_test_piece.cmm.temperature_half_width; seed 004 L2145)",
          std::fabs(parts::measurementDeviationEq76_um(alpha, dT, v.value)) / std::sqrt(3.0));
  } else {
    const double dT = m.ttp.on_machine_temperature_change_K;
    double v2 = 0;
    for (const auto& pr : v.pairs) {
      const double L = (pr.at_i->length_mm + pr.at_0->length_mm) / 2;
      v2 += std::pow(pr.w * v.unit_factor * alpha * 1e-6 * dT * L, 2) / 3.0;
    }
    add("part temperature change between compared features", 'B', "rectangular",
        "alpha dT d per compared pair (feature of cycle i against its reference), " + alphaBasis(m) +
            ", dT within +-" + num(dT) + " K (thermal_test_piece.on_machine.temperature_change), independent pairs",
        std::sqrt(v2));
  }
  // Datum frame.
  double a2 = 0;
  for (const auto& [i, dxi] : ctx.datum_sens) {
    const auto& p = pts[static_cast<std::size_t>(i)];
    const double sigma = sc.type_a_used ? sc.type_a_sigma_mm : p.sigma_b_mm;
    const double gi = G.dot(dxi);
    a2 += (sigma * sigma + p.sigma_res_mm * p.sigma_res_mm) * gi * gi;
  }
  add("datum alignment (TOP, FLANK_P, FLANK_N, CYL)", sc.type_a_used ? 'A' : 'B', "normal",
      std::string("the datum points' scatter") + (ctx.route == TtpRoute::OnMachine ? " and resolution" : "") +
          " through the datum frame (origin, axes) and the sensitivities of the value to it; facets of different cycles "
          "have different normals, Z paths at different y see the tilt",
      std::sqrt(a2), sc.type_a_used ? sc.type_a_dof : kInf);
  return uncertainty::combine(v.quantity, v.unit, v.value, cs, ctx.k);
}

// Eq. 7.10 with its budget from the budget of E_TTP in the radial form (Eq. 7.9).
uncertainty::Budget temperatureBudget(const parts::PlanManifest& m, const uncertainty::Budget& ettp_7_9, double k,
                                      bool predicted) {
  const double alpha = m.ttp.eq_7_10_alpha_um_per_m_K, R = m.ttp.eq_7_10_radius_mm;
  const double aR = alpha * R * 1e-3;  // um per K
  const double dT = -parts::temperatureEquivalentEq710_K(ettp_7_9.value, alpha, R);  // seed 004 Eq. 7.10, docs §4 signs
  std::vector<Contribution> cs;
  for (const auto& c : ettp_7_9.contributions) {
    Contribution x = c;
    x.u = c.u / aR;
    x.basis = c.basis + " (through E_TTP,7.9 / (alpha R))";
    cs.push_back(x);
  }
  const double ua = m.ttp.alpha_u_um_per_m_K;
  cs.push_back({"alpha of Eq. 7.10", 'B', "normal",
                "u(alpha) = " + num(ua) + " um/(m K) (thermal_test_piece.evaluation.alpha_u_um_per_m_K), alpha = " +
                    num(alpha) + " um/(m K) (seed 004 L2177): |dT| u(alpha) / alpha" +
                    (predicted ? ": scales with the measured value" : ""),
                predicted ? 0.0 : std::fabs(dT) * ua / alpha, kInf});
  cs.push_back({"R of Eq. 7.10", 'B', "normal",
                "not stated: R = " + num(R) + " mm is the nominal facet apothem (seed 004 L2177); no uncertainty given", 0, kInf});
  return uncertainty::combine("dT_K", "K", dT, cs, k);
}

std::map<int, std::string> phases(const parts::PlanManifest& m) {
  std::map<int, std::string> out;
  for (const auto& c : m.cut_cycles) out[c.cycle] = c.phase;
  return out;
}

// Cycle times: the mean planned cut time of the cycle's features.
std::map<int, double> cycleTimes(const parts::PlanManifest& m) {
  std::map<int, std::pair<double, int>> acc;
  for (const auto& f : m.features)
    if (f.cycle >= 0 && std::isfinite(f.cut_time_s)) acc[f.cycle].first += f.cut_time_s, ++acc[f.cycle].second;
  std::map<int, double> out;
  for (const auto& [c, a] : acc) out[c] = a.first / a.second;
  for (const auto& c : m.cut_cycles)
    if (!out.count(c.cycle)) out[c.cycle] = (c.start_s + c.end_s) / 2;
  return out;
}

// The manifest's measurement features per cycle and side.
struct CycleFeatures {
  std::map<std::string, const parts::ManifestFeature*> by_side;  // Z, X1, X2, Y1, Y2
};
std::map<int, CycleFeatures> cycleFeatures(const parts::PlanManifest& m) {
  std::map<int, CycleFeatures> out;
  for (const auto& f : m.features) {
    if (f.cycle < 0) continue;
    const auto& n = f.nominal;
    if (n.role == "z_path" || n.role == "facet") out[f.cycle].by_side[n.group] = &f;
  }
  return out;
}

const char* kSides[4] = {"X1", "X2", "Y1", "Y2"};

// One line per cycle: the values left out and the features that are absent.
std::string missingMessage(const std::map<std::string, bool>& ok, const std::vector<std::string>& absent, int cycle,
                           const std::string& why) {
  const bool x = !ok.at("X1") || !ok.at("X2"), y = !ok.at("Y1") || !ok.at("Y2"), z = !ok.at("Z");
  std::string q;
  auto add = [&](const char* name) { q += (q.empty() ? "" : ", ") + std::string(name); };
  if (x) add("EX_um");
  if (y) add("EY_um");
  if (z) add("EZ_um"), add("EB_urad");
  if (x || y) add("ETTP_um"), add("dT_K");
  std::string ids;
  for (const auto& a : absent) ids += (ids.empty() ? "" : ", ") + a;
  return q + " not evaluated: " + ids + " (cycle " + std::to_string(cycle) + ") " + (absent.size() == 1 ? "has " : "have ") + why;
}

// The manifest's rules (parts::thermalTestPieceEvaluation), for the gauge route those of the
// values it gives.
std::vector<parts::EvaluationRule> formulas(const parts::PlanManifest& m, TtpRoute route) {
  if (route != TtpRoute::Gauge) return m.evaluation;
  std::vector<parts::EvaluationRule> out;
  for (const auto& r : m.evaluation)
    if (r.output == "EX_um" || r.output == "EY_um" || r.output == "ETTP_um" || r.output == "dT_K") out.push_back(r);
  return out;
}

uncertainty::Budget zeroBudget(const std::string& q, const std::string& unit, double k) {
  return uncertainty::combine(q, unit, 0.0, {}, k);
}

// A cycle's row before its values: its phase (cycle 0: the reference) and time.
template <class Phases, class Times>
TtpCycleResult cycleResult(int c, const Phases& ph, const Times& times) {
  TtpCycleResult cr;
  cr.cycle = c;
  cr.phase = ph.count(c) ? ph.at(c) : (c == 0 ? "reference" : "");
  cr.time_s = times.count(c) ? times.at(c) : 0.0;
  return cr;
}

const char* kQuantities[6] = {"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um", "dT_K"};
const char* kUnits[6] = {"um", "um", "um", "urad", "um", "K"};

TtpEvaluation evaluateImpl(const parts::PlanManifest& m, const TtpPoints& in, const TtpOptions& opt, bool predicted) {
  if (m.kind != "thermal_test_piece")
    throw InputError(m.file, 0, "manifest kind '" + m.kind + "': this evaluation is for the thermal test piece");
  TtpEvaluation e;
  e.manifest_file = m.file;
  e.input_file = in.file;
  e.format = in.format;
  e.assigned_by = in.assigned_by;
  e.route = in.route;
  e.points = static_cast<int>(in.points.size());
  e.coverage_k = opt.coverage_k;
  e.formulas = formulas(m, in.route);
  const std::string& file = in.file;

  // Points grouped by feature, in file order.
  std::vector<Pt> pts;
  std::map<std::string, std::vector<int>> by;
  for (const auto& p : in.points) {
    if (!m.feature(p.feature))
      throw InputError(file, p.line, "feature '" + p.feature + "' is not in the manifest " + m.file);
    Pt q;
    q.feature = p.feature;
    q.line = p.line;
    q.file_mm = p.p_mm;
    by[p.feature].push_back(static_cast<int>(pts.size()));
    pts.push_back(q);
  }

  // Datum frame.
  DatumSets ds;
  std::map<std::string, std::vector<Vector3d>*> datum_of{{"TOP", &ds.top}, {"FLANK_P", &ds.flank_p}, {"FLANK_N", &ds.flank_n}, {"CYL", &ds.cyl}};
  const std::map<std::string, std::string> needs{{"TOP", ">= 3 non-collinear points on the top face"},
                                                 {"FLANK_P", ">= 3 non-collinear points on the flank"},
                                                 {"FLANK_N", ">= 3 non-collinear points on the flank"},
                                                 {"CYL", ">= 3 points around the datum band"}};
  for (const auto& [id, set] : datum_of) {
    const auto it = by.find(id);
    if (it == by.end() || it->second.size() < 3)
      featureError(file, pts, it == by.end() ? std::vector<int>{} : it->second, id,
                   "the datum " + id + " needs " + needs.at(id) + " (seed 004 L2055: the part frame)");
    for (int i : it->second) set->push_back(pts[static_cast<std::size_t>(i)].file_mm);
  }
  FrameFits ff;
  try {
    ff = buildFrame(ds);
  } catch (const DatumFailure& x) {
    featureError(file, pts, by.at(x.id), x.id, "the datum " + x.id + " does not define its element: " + x.what());
  } catch (const GeometryError& x) {
    throw InputError(file, 0, std::string("datum frame (TOP, FLANK_P, FLANK_N, CYL): ") + x.what());
  }
  const TtpFrame& frame = ff.frame;
  for (auto& p : pts) p.part_mm = frame.toPart(p.file_mm);

  // Scatter per point.
  const double sigma_spec_om = m.probe_repeatability_2sigma_um / 2 * 1e-3;
  for (auto& p : pts) {
    if (in.route == TtpRoute::Cmm) {
      const double L = p.part_mm.norm();
      const double mpe = m.ttp.cmm.mpe_constant_um + (m.ttp.cmm.mpe_length_mm > 0 ? L / m.ttp.cmm.mpe_length_mm : 0.0);
      p.sigma_b_mm = mpe / 2 * 1e-3;
    } else {
      p.sigma_b_mm = sigma_spec_om;
      p.sigma_res_mm = m.coordinate_resolution_mm / std::sqrt(12.0);
    }
  }

  // Alignment report.
  {
    TtpAlignment a;
    a.frame = frame;
    const Eigen::AngleAxisd aa(frame.R);
    a.rotation_urad = aa.axis() * aa.angle() * 1e6;
    a.translation_um = -(frame.R * frame.origin_mm) * 1e3;
    auto form = [&](const std::vector<Vector3d>& v, geometry::ElementKind kind, const geometry::FitResult& ls) {
      if (!opt.form_mz) return ls.form_mm * 1e3;
      try {
        return geometry::fitMinimumZone(kind, v).form_mm * 1e3;
      } catch (const GeometryError&) {
        return ls.form_mm * 1e3;
      }
    };
    geometry::Points3 q;
    for (const auto& p : ds.cyl) {
      const Vector3d r = frame.toPart(p);
      q.emplace_back(r.x(), r.y(), 0.0);
    }
    a.datums.push_back({"TOP", static_cast<int>(ds.top.size()), form(ds.top, geometry::ElementKind::Plane, ff.top)});
    a.datums.push_back({"FLANK_P", static_cast<int>(ds.flank_p.size()), form(ds.flank_p, geometry::ElementKind::Plane, ff.flank_p)});
    a.datums.push_back({"FLANK_N", static_cast<int>(ds.flank_n.size()), form(ds.flank_n, geometry::ElementKind::Plane, ff.flank_n)});
    a.datums.push_back({"CYL", static_cast<int>(ds.cyl.size()), form(q, geometry::ElementKind::Circle2D, ff.cyl)});
    e.alignment = a;
  }

  // Measurement features: one LS plane each (part frame).
  const auto times = cycleTimes(m);
  std::map<std::string, PlaneModel> planes;
  e.features.reserve(m.features.size());
  for (const auto& mf : m.features) {
    const auto& n = mf.nominal;
    if (n.role != "z_path" && n.role != "facet") continue;
    const auto it = by.find(n.id);
    if (it == by.end()) continue;
    const auto& idx = it->second;
    if (idx.size() < 3) featureError(file, pts, idx, n.id, "a plane needs >= 3 non-collinear points");
    std::vector<Vector3d> v;
    for (int i : idx) v.push_back(pts[static_cast<std::size_t>(i)].part_mm);
    PlaneModel pm;
    try {
      pm = fitPlaneModel(v, idx, n.direction, opt.form_mz);
    } catch (const GeometryError& x) {
      featureError(file, pts, idx, n.id, x.what());
    }
    // The fitted plane against its nominal one: mislabelled points (X1_3's labelled X1_4) would
    // otherwise give errors off by tenths of a mm silently, and a Z path's depth divides by n_z.
    {
      const Vector3d nn = n.direction.normalized();
      const double angle_deg = radToDeg(std::acos(std::clamp(pm.n.dot(nn), -1.0, 1.0)));
      const double off_mm = (pm.c - n.point_mm).dot(nn);
      if (angle_deg > kNominalAngleDeg || std::fabs(off_mm) > kNominalDistanceMm)
        throw InputError(file, pts[static_cast<std::size_t>(idx.front())].line,
                         "feature " + n.id + " (" + std::to_string(idx.size()) + " points, the first on this line): after the datum "
                         "alignment its fitted plane's normal is " + num(angle_deg) + " deg from the nominal one and its centre " +
                             num(off_mm) + " mm from the nominal surface (at most " + num(kNominalAngleDeg) + " deg and " +
                             num(kNominalDistanceMm) + " mm): mislabelled points? (manifest " + m.file + ")");
    }
    TtpFeatureResult f;
    f.id = n.id;
    f.group = n.group;
    f.index = n.index;
    f.cycle = mf.cycle;
    f.time_s = std::isfinite(mf.cut_time_s) ? mf.cut_time_s : (times.count(mf.cycle) ? times.at(mf.cycle) : 0.0);
    f.points = static_cast<int>(idx.size());
    f.rms_um = pm.rms_mm * 1e3;
    f.form_mz_um = (pm.form_mz_mm >= 0 ? pm.form_mz_mm : pm.form_ls_mm) * 1e3;
    f.centre_mm = pm.c;
    f.normal = pm.n;
    planes[n.id] = pm;
    e.features.push_back(f);
  }

  // Type A: pooled residual of the measurement-feature fits.
  {
    double ssr = 0, dof = 0, sb2 = 0;
    int nb = 0;
    for (const auto& [id, p] : planes) {
      ssr += p.ssr_mm2;
      dof += p.dof;
      for (int i : p.pts) sb2 += std::pow(pts[static_cast<std::size_t>(i)].sigma_b_mm, 2), ++nb;
    }
    e.scatter.type_b_sigma_mm = nb ? std::sqrt(sb2 / nb) : sigma_spec_om;
    if (dof > 0 && !predicted) {
      e.scatter.type_a_sigma_mm = std::sqrt(ssr / dof);
      e.scatter.type_a_dof = dof;
    }
    e.scatter.type_a_used = e.scatter.type_a_dof > 0 && e.scatter.type_a_sigma_mm > e.scatter.type_b_sigma_mm;
  }

  // Quantities per feature.
  std::map<std::string, FQ> dq, zq, bq;
  for (auto& f : e.features) {
    const auto& pm = planes.at(f.id);
    const auto& nom = m.feature(f.id)->nominal;
    if (nom.role == "facet") {
      dq[f.id] = quantity(f, pm, Q::D, 0);
      f.d_mm = dq[f.id].value;
    } else {
      zq[f.id] = quantity(f, pm, Q::DZ, nom.point_mm.y());
      bq[f.id] = quantity(f, pm, Q::Beta, nom.point_mm.y());
      f.depth_mm = zq[f.id].value;
      f.beta_urad = bq[f.id].value;
    }
    const FQ& main = nom.role == "facet" ? dq[f.id] : zq[f.id];
    double v = 0;
    for (std::size_t j = 0; j < main.pts.size(); ++j) {
      const auto& p = pts[static_cast<std::size_t>(main.pts[j])];
      const double s = e.scatter.type_a_used ? e.scatter.type_a_sigma_mm : p.sigma_b_mm;
      v += std::pow(s * main.s[j], 2);
    }
    f.u_d_um = std::sqrt(v) * 1e3;
  }

  // Frame sensitivities to every datum point (central differences of the construction).
  BudgetContext ctx;
  ctx.m = &m;
  ctx.route = in.route;
  ctx.pts = &pts;
  ctx.scatter = e.scatter;
  ctx.predicted = predicted;
  ctx.k = opt.coverage_k;
  if (opt.budgets) {
    const Vector3d z_file = frame.R.row(2).transpose();
    for (const auto& [id, set] : datum_of) {
      const auto& idx = by.at(id);
      for (std::size_t j = 0; j < idx.size(); ++j) {
        // Each datum point displaced along its surface normal (the sign is immaterial).
        Vector3d dir;
        if (id == "TOP") {
          dir = z_file;
        } else if (id == "FLANK_P") {
          dir = ff.flank_p.element.direction;
        } else if (id == "FLANK_N") {
          dir = ff.flank_n.element.direction;
        } else {
          const Vector3d r = frame.toPart((*set)[j]);
          dir = frame.R.transpose() * Vector3d(r.x(), r.y(), 0.0).normalized();
        }
        DatumSets plus = ds, minus = ds;
        datumSet(plus, id)[j] += kFrameStepMm * dir;
        datumSet(minus, id)[j] -= kFrameStepMm * dir;
        const auto fp = buildFrame(plus).frame, fm = buildFrame(minus).frame;
        ctx.datum_sens.push_back({idx[j], (frameDelta(frame, fp) - frameDelta(frame, fm)) / (2 * kFrameStepMm)});
      }
    }
  }

  // Cycles.
  const auto cf = cycleFeatures(m);
  const auto ph = phases(m);
  if (!cf.count(0)) throw InputError(m.file, 0, "the manifest lists no reference features (cycle 0)");
  const auto& ref = cf.at(0);
  auto have = [&](const parts::ManifestFeature* f) { return f && planes.count(f->nominal.id); };
  for (const auto& [side, f] : ref.by_side)
    if (!have(f))
      throw InputError(file, 0, "the reference feature " + f->nominal.id + " (cycle 0) has no points: a missing reference cut; every "
                                "value of its side is measured against it (manifest " + m.file + ")");
  for (const char* s : {"Z", "X1", "X2", "Y1", "Y2"})
    if (!ref.by_side.count(s)) throw InputError(m.file, 0, std::string("the manifest has no reference ") + s + " feature (cycle 0)");

  // Not a structured binding: lambdas below use feats, which clang before 16 cannot capture
  // (C++20 P1091; scripts/fuzz.sh builds with clang 14).
  for (const auto& entry : cf) {
    const auto& c = entry.first;
    const auto& feats = entry.second;
    TtpCycleResult cr = cycleResult(c, ph, times);
    if (c == 0) {
      for (int j = 0; j < 6; ++j) cr.values.push_back(zeroBudget(kQuantities[j], kUnits[j], opt.coverage_k));
      cr.ETTP_7_9_um = 0;  // the printed forms of Eqs. 7.1/7.2 are defined for i >= 1 only
      e.cycles.push_back(cr);
      continue;
    }
    std::map<std::string, bool> ok;
    std::vector<std::string> absent;
    for (const char* s : {"Z", "X1", "X2", "Y1", "Y2"}) {
      const auto it = feats.by_side.find(s);
      ok[s] = it != feats.by_side.end() && have(it->second);
      if (!ok[s]) absent.push_back(it != feats.by_side.end() ? it->second->nominal.id : std::string(s) + " (not in the manifest)");
    }
    if (!absent.empty()) cr.missing.push_back(missingMessage(ok, absent, c, "no points in " + file));
    auto id = [&](const std::map<std::string, const parts::ManifestFeature*>& b, const char* s) { return b.at(s)->nominal.id; };
    parts::TtpMeasures mi, m0;
    auto fill = [&](parts::TtpMeasures& mm, const CycleFeatures& cfs, bool all) {
      auto val = [&](std::map<std::string, FQ>& mq, const char* s) {
        return (all || ok[s]) ? mq[id(cfs.by_side, s)].value : 0.0;
      };
      mm.d_X1_mm = val(dq, "X1");
      mm.d_X2_mm = val(dq, "X2");
      mm.d_Y1_mm = val(dq, "Y1");
      mm.d_Y2_mm = val(dq, "Y2");
      mm.d_Z_mm = val(zq, "Z");
      mm.beta_urad = val(bq, "Z");
    };
    fill(mi, feats, false);
    fill(m0, ref, true);
    const auto te = parts::ttpErrors(mi, m0);
    auto pair = [&](std::map<std::string, FQ>& mq, const char* s, double w) {
      return Pair{&mq[id(feats.by_side, s)], &mq[id(ref.by_side, s)], w};
    };
    std::vector<ValueSpec> specs;
    if (ok["X1"] && ok["X2"]) {
      specs.push_back({"EX_um", "um", te.EX_um, {pair(dq, "X2", 0.5), pair(dq, "X1", -0.5)}, 1e3, false});  // seed 004 Eq. 7.1
      cr.EX_printed_um = te.EX_printed_um;
    }
    if (ok["Y1"] && ok["Y2"]) {
      specs.push_back({"EY_um", "um", te.EY_um, {pair(dq, "Y2", 0.5), pair(dq, "Y1", -0.5)}, 1e3, false});  // seed 004 Eq. 7.2
      cr.EY_printed_um = te.EY_printed_um;
    }
    if (ok["Z"]) {
      specs.push_back({"EZ_um", "um", te.EZ_um, {pair(zq, "Z", 1.0)}, 1e3, false});        // seed 004 Eq. 7.4
      specs.push_back({"EB_urad", "urad", te.EB_urad, {pair(bq, "Z", 1.0)}, 1.0, true});   // seed 004 Eq. 7.5
    }
    const bool facets = ok["X1"] && ok["X2"] && ok["Y1"] && ok["Y2"];
    ValueSpec radial;
    if (facets) {
      specs.push_back({"ETTP_um", "um", te.ETTP_7_3_um,  // seed 004 Eq. 7.3
                       {pair(dq, "X1", 0.5), pair(dq, "X2", 0.5), pair(dq, "Y1", 0.5), pair(dq, "Y2", 0.5)}, 1e3, false});
      radial = {"ETTP_7_9_um", "um", te.ETTP_7_9_um,  // seed 004 Eq. 7.9
                {pair(dq, "X1", 0.25), pair(dq, "X2", 0.25), pair(dq, "Y1", 0.25), pair(dq, "Y2", 0.25)}, 1e3, false};
      cr.ETTP_7_9_um = te.ETTP_7_9_um;
    }
    for (const auto& s : specs)
      cr.values.push_back(opt.budgets ? valueBudget(s, ctx) : uncertainty::combine(s.quantity, s.unit, s.value, {}, opt.coverage_k));
    if (facets) {
      const auto rb = opt.budgets ? valueBudget(radial, ctx) : uncertainty::combine(radial.quantity, "um", radial.value, {}, opt.coverage_k);
      cr.values.push_back(temperatureBudget(m, rb, opt.coverage_k, predicted));
    }
    e.cycles.push_back(cr);
  }
  e.spans = ttpSpans(e.cycles);
  return e;
}

}  // namespace

TtpFrame ttpDatumFrame(const TtpPoints& points) {
  DatumSets ds;
  for (const auto& p : points.points) {
    if (p.feature == "TOP") ds.top.push_back(p.p_mm);
    if (p.feature == "FLANK_P") ds.flank_p.push_back(p.p_mm);
    if (p.feature == "FLANK_N") ds.flank_n.push_back(p.p_mm);
    if (p.feature == "CYL") ds.cyl.push_back(p.p_mm);
  }
  for (const auto& [id, v] : std::map<std::string, std::size_t>{{"TOP", ds.top.size()}, {"FLANK_P", ds.flank_p.size()},
                                                                {"FLANK_N", ds.flank_n.size()}, {"CYL", ds.cyl.size()}})
    if (v < 3)
      throw InputError(points.file, 0, "the datum " + id + " has " + std::to_string(v) + " points; it needs >= 3 (seed 004 L2055)");
  try {
    return buildFrame(ds).frame;
  } catch (const DatumFailure& x) {
    throw InputError(points.file, 0, "the datum " + x.id + " does not define its element: " + x.what());
  } catch (const GeometryError& x) {
    throw InputError(points.file, 0, std::string("datum frame: ") + x.what());
  }
}

TtpEvaluation evaluateThermalTestPiece(const parts::PlanManifest& m, const TtpPoints& points, const TtpOptions& options) {
  return evaluateImpl(m, points, options, false);
}

// --- dial gauge (seed 004 Eqs. 7.7-7.9) -------------------------------------------------------

TtpEvaluation evaluateThermalTestPieceGauge(const parts::PlanManifest& m, const TtpGaugeReadings& r, const TtpOptions& opt) {
  if (m.kind != "thermal_test_piece")
    throw InputError(m.file, 0, "manifest kind '" + m.kind + "': this evaluation is for the thermal test piece");
  TtpEvaluation e;
  e.manifest_file = m.file;
  e.input_file = r.file;
  e.format = "gauge";
  e.assigned_by = "labels";
  e.route = TtpRoute::Gauge;
  e.points = static_cast<int>(r.readings.size());
  e.coverage_k = opt.coverage_k;
  e.formulas = formulas(m, TtpRoute::Gauge);
  e.gauge_resolution_um = opt.gauge_resolution_um;
  const double u_read = opt.gauge_resolution_um / std::sqrt(12.0);
  e.scatter.type_b_sigma_mm = u_read * 1e-3;
  e.notes.push_back("E_Z and E_B are not available from the dial gauge on the facets (seed 004 L2121 measures the Z paths with a "
                    "separate depth gauge set-up)");
  e.notes.push_back("the readings are g = d(t_i) - d(t_0) per facet, so Eqs. 7.7-7.9 are the formulas below with g for the "
                    "changes of d; E_TTP is Eq. 7.3 (diametral) as on the other routes: (g_X1 + g_X2 + g_Y1 + g_Y2) / 2, twice "
                    "Eq. 7.9's radial mean, which is reported as ETTP_7_9_um and gives dT (Eq. 7.10)");
  e.notes.push_back("gauge uncertainty: the thesis states none; the budget reads the gauge resolution (" +
                    num(opt.gauge_resolution_um) + " um, --gauge-resolution-um) as rectangular per reading and per zero setting");
  std::map<std::string, double> g;
  for (const auto& x : r.readings) g[x.facet] = x.g_um;
  const auto cf = cycleFeatures(m);
  const auto ph = phases(m);
  const auto times = cycleTimes(m);
  if (!cf.count(0)) throw InputError(m.file, 0, "the manifest lists no reference features (cycle 0)");
  const auto& ref = cf.at(0);
  for (const char* s : kSides)
    if (!ref.by_side.count(s))
      throw InputError(m.file, 0, std::string("the manifest has no reference ") + s +
                                      " facet (cycle 0): the dial-gauge readings of that side are relative to it (seed 004 L2121)");
  auto reading = [&](const parts::ManifestFeature* f, const parts::ManifestFeature* f0) -> std::optional<double> {
    if (!f || !g.count(f->nominal.id)) return std::nullopt;
    return g.at(f->nominal.id) - (g.count(f0->nominal.id) ? g.at(f0->nominal.id) : 0.0);  // relative to the reference facet
  };
  const double alpha = m.material_alpha_um_per_m_K;
  const double dT = m.ttp.on_machine_temperature_change_K;
  // Not a structured binding: lambdas below use feats, which clang before 16 cannot capture
  // (C++20 P1091; scripts/fuzz.sh builds with clang 14).
  for (const auto& entry : cf) {
    const auto& c = entry.first;
    const auto& feats = entry.second;
    TtpCycleResult cr = cycleResult(c, ph, times);
    if (c == 0) {
      for (int j : {0, 1, 4, 5}) cr.values.push_back(zeroBudget(kQuantities[j], kUnits[j], opt.coverage_k));
      cr.ETTP_7_9_um = 0;
      e.cycles.push_back(cr);
      continue;
    }
    cr.missing.push_back("EZ_um, EB_urad: not measured by the dial gauge on the facets (seed 004 Eqs. 7.7-7.9)");
    std::map<std::string, std::optional<double>> v;
    std::map<std::string, bool> ok{{"Z", true}};
    std::vector<std::string> absent;
    for (const char* s : kSides) {
      const auto it = feats.by_side.find(s);
      v[s] = it == feats.by_side.end() ? std::nullopt : reading(it->second, ref.by_side.at(s));
      ok[s] = v[s].has_value();
      if (!ok[s]) absent.push_back(it == feats.by_side.end() ? std::string(s) + " (not in the manifest)" : it->second->nominal.id);
    }
    if (!absent.empty()) cr.missing.push_back(missingMessage(ok, absent, c, "no reading in " + r.file));
    const auto ge = parts::gaugeErrors(v["X1"].value_or(0), v["X2"].value_or(0), v["Y1"].value_or(0), v["Y2"].value_or(0));
    auto budget = [&](const std::string& q, double value, const std::vector<std::pair<const char*, double>>& w) {
      std::vector<Contribution> cs;
      double w2 = 0, t2 = 0;
      for (const auto& [s, wi] : w) {
        w2 += wi * wi;
        const double L = m.feature(feats.by_side.at(s)->nominal.id)->nominal.point_mm.head<2>().norm();
        if (std::isfinite(alpha)) t2 += std::pow(wi * alpha * 1e-6 * dT * L * 1e3, 2) / 3.0;
      }
      const std::string basis = "resolution " + num(opt.gauge_resolution_um) +
                                " um (--gauge-resolution-um; not stated in the thesis), rectangular, res/sqrt(12)";
      cs.push_back({"dial gauge readings", 'B', "rectangular", basis + " per reading", u_read * std::sqrt(w2), kInf});
      cs.push_back({"dial gauge zero on the reference facets", 'B', "rectangular", basis + " per side's zero setting",
                    u_read * std::sqrt(w2), kInf});
      if (std::isfinite(alpha))
        cs.push_back({"part temperature change between compared facets", 'B', "rectangular",
                      "alpha dT d per facet against its reference, " + alphaBasis(m) + ", dT within +-" + num(dT) +
                          " K (thermal_test_piece.on_machine.temperature_change)",
                      std::sqrt(t2), kInf});
      else
        cs.push_back({"part temperature change between compared facets", 'B', "rectangular",
                      "not stated: set blank.material.alpha_um_per_m_K in the part file", 0, kInf});
      return uncertainty::combine(q, "um", value, cs, opt.coverage_k);
    };
    if (v["X1"] && v["X2"]) cr.values.push_back(budget("EX_um", ge.EX_um, {{"X2", 0.5}, {"X1", -0.5}}));  // seed 004 Eq. 7.7
    if (v["Y1"] && v["Y2"]) cr.values.push_back(budget("EY_um", ge.EY_um, {{"Y2", 0.5}, {"Y1", -0.5}}));  // seed 004 Eq. 7.8
    if (v["X1"] && v["X2"] && v["Y1"] && v["Y2"]) {
      // Eq. 7.3 with g = d(t_i) - d(t_0): [(g_X1 + g_X2) + (g_Y1 + g_Y2)] / 2, exactly twice Eq. 7.9.
      cr.values.push_back(budget("ETTP_um", 2 * ge.ETTP_um, {{"X1", 0.5}, {"X2", 0.5}, {"Y1", 0.5}, {"Y2", 0.5}}));
      const auto radial = budget("ETTP_7_9_um", ge.ETTP_um, {{"X1", 0.25}, {"X2", 0.25}, {"Y1", 0.25}, {"Y2", 0.25}});  // seed 004 Eq. 7.9
      cr.ETTP_7_9_um = ge.ETTP_um;
      cr.values.push_back(temperatureBudget(m, radial, opt.coverage_k, false));
    }
    e.cycles.push_back(cr);
  }
  e.spans = ttpSpans(e.cycles);
  return e;
}

// --- spans (Table 7.2) -------------------------------------------------------------------

std::vector<TtpSpan> ttpSpans(const std::vector<TtpCycleResult>& cycles) {
  std::vector<TtpSpan> out;
  if (cycles.empty()) return out;
  int last = 0;
  for (const auto& c : cycles) last = std::max(last, c.cycle);
  std::vector<int> ends;
  for (int l : {1, last / 2, last})
    if (l >= 1 && (ends.empty() || l > ends.back())) ends.push_back(l);
  const TtpCycleResult* c0 = nullptr;
  for (const auto& c : cycles)
    if (c.cycle == 0) c0 = &c;
  for (int l : ends) {
    TtpSpan s;
    s.first = 0;
    s.last = l;
    double t_last = 0;
    for (const auto& c : cycles)
      if (c.cycle == l) t_last = c.time_s;
    s.period_h = c0 ? (t_last - c0->time_s) / 3600 : 0;
    for (const char* q : {"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um"}) {
      // Every cycle 0..l must have the value: a span over the cycles that happen to be there
      // would read as the period's span.
      std::map<int, const uncertainty::Budget*> at;
      for (const auto& c : cycles)
        if (c.cycle <= l && c.value(q)) at[c.cycle] = c.value(q);
      bool measured = false;  // a quantity this route gives at all in the period
      for (const auto& [c, b] : at) measured = measured || c > 0;
      if (!measured) continue;
      TtpSpanValue v;
      v.quantity = q;
      for (int c = 0; c <= l; ++c)
        if (!at.count(c)) v.missing_cycles.push_back(c);
      if (v.complete()) {
        const uncertainty::Budget* hi = nullptr;
        const uncertainty::Budget* lo = nullptr;
        for (const auto& [c, b] : at) {
          if (!hi || b->value > hi->value) hi = b;
          if (!lo || b->value < lo->value) lo = b;
        }
        // The two extremes' U combined as if independent: conservative (both share the reference
        // cut, which cancels in their difference) and blind to another cycle being the true extreme.
        v.span = hi->value - lo->value;
        v.U = std::sqrt(hi->U * hi->U + lo->U * lo->U);
      }
      s.values.push_back(v);
    }
    out.push_back(s);
  }
  return out;
}

std::string cycleRanges(const std::vector<int>& c) {
  std::string out;
  for (std::size_t i = 0; i < c.size();) {
    std::size_t j = i;
    while (j + 1 < c.size() && c[j + 1] == c[j] + 1) ++j;
    out += (out.empty() ? "" : ", ") + std::to_string(c[i]) + (j > i ? "-" + std::to_string(c[j]) : "");
    i = j + 1;
  }
  return out;
}

TtpComparison compareSpans(const TtpEvaluation& e, const std::string& other) {
  using nlohmann::json;
  json j;
  try {
    j = json::parse(readFile(other));
  } catch (const json::parse_error& x) {
    throw InputError(other, 0, std::string("not valid JSON: ") + x.what());
  }
  TtpComparison c;
  c.against = other;
  c.this_route = ttpRouteName(e.route);
  try {
    if (j.value("format", "") != "probeloop-evaluation" || j.value("kind", "") != "thermal_test_piece")
      throw InputError(other, 0,
                       "not a thermal-test-piece evaluation.json (format probeloop-evaluation, kind thermal_test_piece; found kind '" +
                           j.value("kind", "") + "')");
    c.other_route = j.at("input").at("route").get<std::string>();
    // The same quantity on both sides: the formula of each compared output must be this run's.
    auto formulaOf = [](const std::vector<parts::EvaluationRule>& rules, const std::string& q) -> const parts::EvaluationRule* {
      for (const auto& r : rules)
        if (r.output == q) return &r;
      return nullptr;
    };
    auto otherFormula = [&](const std::string& q) -> std::string {
      for (const auto& f : j.at("formulas"))
        if (f.at("output").get<std::string>() == q) return f.at("formula").get<std::string>();
      return "";
    };
    auto sameQuantity = [&](const std::string& q) {
      const auto* mine = formulaOf(e.formulas, q);
      const std::string theirs = otherFormula(q);
      if (!mine || theirs != mine->formula)
        throw InputError(other, 0,
                         q + " is not the same quantity in both evaluations: this run (route " + c.this_route + ") computes '" +
                             (mine ? mine->formula : std::string("(no formula)")) + "', " + other + " (route " + c.other_route +
                             ") '" + (theirs.empty() ? std::string("(no formula)") : theirs) +
                             "'; re-evaluate it with this probeloop so that both use the same formulas");
    };
    for (const auto& s : e.spans) {
      const json* match = nullptr;
      for (const auto& o : j.at("spans"))
        if (o.at("cycles").at(0).get<int>() == s.first && o.at("cycles").at(1).get<int>() == s.last) match = &o;
      if (!match) continue;
      const std::string period = "cycles " + std::to_string(s.first) + "-" + std::to_string(s.last);
      for (const auto& v : s.values)
        for (const auto& ov : match->at("values")) {
          if (ov.at("quantity").get<std::string>() != v.quantity) continue;
          sameQuantity(v.quantity);
          const auto other_missing = ov.at("missing_cycles").get<std::vector<int>>();
          if (!v.complete() || !other_missing.empty()) {
            c.left_out.push_back(period + " " + v.quantity + ": incomplete in " +
                                 (!v.complete() ? "this run (cycles " + cycleRanges(v.missing_cycles) + " missing)" : std::string()) +
                                 (!v.complete() && !other_missing.empty() ? " and in " : "") +
                                 (!other_missing.empty() ? other + " (cycles " + cycleRanges(other_missing) + " missing)" : std::string()));
            continue;
          }
          TtpComparisonRow r;
          r.period_h = s.period_h;
          r.quantity = v.quantity;
          r.this_span = v.span;
          r.other_span = ov.at("span").get<double>();
          if (std::fabs(v.span) > 0) r.reduction_percent = parts::spanReductionPercent(v.span, r.other_span);  // Table 7.2
          c.rows.push_back(r);
        }
    }
  } catch (const json::exception& x) {
    throw InputError(other, 0, std::string("input.route, spans or formulas missing or of the wrong type: ") + x.what());
  }
  if (c.rows.empty()) {
    std::string why;
    for (const auto& l : c.left_out) why += "; " + l;
    throw InputError(other, 0,
                     "no complete span of this evaluation (cycles 0-1, 0-half, 0-last) has a complete span of the same cycles in the "
                     "other: nothing to compare" + why);
  }
  return c;
}

// --- the planner's prediction -----------------------------------------------------------------

TtpPrediction predictThermalTestPiece(const parts::PlanManifest& m, double k) {
  TtpPrediction out;
  if (m.points.empty()) {
    out.note = "the manifest lists no probe points: nothing to predict";
    return out;
  }
  TtpPoints pts;
  pts.file = m.file;
  pts.assigned_by = "labels";
  for (const auto& p : m.points) {
    TtpPoint q;
    q.feature = p.feature;
    q.point = p.point;
    q.p_mm = machineToPart(m, p.contact_mm + m.tip_radius_mm * p.approach.normalized(), p.c_deg);
    pts.points.push_back(q);
  }
  TtpOptions o;
  o.coverage_k = k;
  o.form_mz = false;
  for (TtpRoute route : {TtpRoute::Cmm, TtpRoute::OnMachine}) {
    pts.route = route;
    TtpEvaluation e;
    try {
      e = evaluateImpl(m, pts, o, true);
    } catch (const InputError& x) {
      out.note = std::string("no prediction from the planned points: ") + x.what();
      return out;
    }
    auto& dst = route == TtpRoute::Cmm ? out.cmm : out.on_machine;
    for (int j = 0; j < 6; ++j) {
      TtpPredictedValue best;
      best.quantity = kQuantities[j];
      best.unit = kUnits[j];
      bool any = false;
      for (const auto& c : e.cycles) {
        if (c.cycle == 0) continue;
        const auto* b = c.value(kQuantities[j]);
        if (!b) continue;
        if (!any || b->U > best.U) {
          best.U = b->U;
          best.cycle = c.cycle;
          best.largest = b->contributions.empty() ? "" : b->contributions.front().input;
          any = true;
        }
      }
      if (any) dst.push_back(best);
    }
  }
  return out;
}

}  // namespace probeloop::evaluate
