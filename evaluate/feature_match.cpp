#include "evaluate/feature_match.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"

namespace probeloop::evaluate {

namespace {

constexpr double kAngleDeg = 1.0, kNormalMm = 0.5, kExtentMarginMm = 1.0, kDiameterMm = 1.0, kAmbiguityMm = 0.05;

// Which nominal kind a row's kind can be: a CMM reports a short bore or boss as a circle.
bool compatible(const std::string& row_kind, const std::string& nominal_kind) {
  if (row_kind == nominal_kind) return true;
  return row_kind == "circle" && nominal_kind == "cylinder";
}

double angleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, bool either_sense) {
  double c = a.normalized().dot(b.normalized());
  if (either_sense) c = std::fabs(c);
  return radToDeg(std::acos(std::clamp(c, -1.0, 1.0)));
}

// The distance that ranks the candidates (mm), whether the row fits within the rules, and the
// rules it fails.
struct Fit {
  double distance_mm = std::numeric_limits<double>::infinity();
  double away_mm = std::numeric_limits<double>::infinity();  // from the feature's nominal surface within its extent
  std::string why;                                            // the rules it fails, "" when it fits
  bool fits() const { return why.empty(); }
};

Fit fitTo(const FeatureActual& r, const parts::NominalFeature& n) {
  Fit f;
  auto fail = [&](bool bad, const std::string& what, double v, const char* unit, double max) {
    if (bad) f.why += (f.why.empty() ? "" : ", ") + what + " " + formatSignificant4(v) + " " + unit + " (at most " + formatSignificant4(max) + ")";
  };
  const Eigen::Vector3d d = r.location_mm - n.point_mm;
  if (n.kind == "plane") {
    const Eigen::Vector3d nn = n.direction.normalized();
    f.distance_mm = std::fabs(d.dot(nn));
    const double out_u = std::max(0.0, std::fabs(d.dot(n.u)) - n.half_u_mm), out_v = std::max(0.0, std::fabs(d.dot(n.v())) - n.half_v_mm);
    f.away_mm = std::sqrt(f.distance_mm * f.distance_mm + out_u * out_u + out_v * out_v);
    const double angle = angleDeg(r.direction, nn, true);
    fail(angle > kAngleDeg, "normal off by", angle, "deg", kAngleDeg);
    fail(f.distance_mm > kNormalMm, "off its plane by", f.distance_mm, "mm", kNormalMm);
    fail(std::max(out_u, out_v) > kExtentMarginMm, "beyond its face by", std::max(out_u, out_v), "mm", kExtentMarginMm);
  } else if (n.kind == "cylinder") {
    const Eigen::Vector3d a = n.direction.normalized();
    f.distance_mm = f.away_mm = (d - d.dot(a) * a).norm();
    const double angle = angleDeg(r.direction, a, true);
    fail(angle > kAngleDeg, "axis off by", angle, "deg", kAngleDeg);
    fail(f.distance_mm > kNormalMm, "off its axis by", f.distance_mm, "mm", kNormalMm);
    if (std::isfinite(r.size_mm))
      fail(std::fabs(r.size_mm - 2 * n.radius_mm) > kDiameterMm, "diameter off by", std::fabs(r.size_mm - 2 * n.radius_mm), "mm", kDiameterMm);
  } else if (n.kind == "sphere") {
    f.distance_mm = f.away_mm = d.norm();
    fail(f.distance_mm > kNormalMm, "centre off by", f.distance_mm, "mm", kNormalMm);
    if (std::isfinite(r.size_mm))
      fail(std::fabs(r.size_mm - 2 * n.radius_mm) > kDiameterMm, "diameter off by", std::fabs(r.size_mm - 2 * n.radius_mm), "mm", kDiameterMm);
  } else {
    f.why = "no nominal geometry of kind " + n.kind;
  }
  return f;
}

std::string where(const FeatureActual& r) { return "the row at line " + std::to_string(r.line) + " ('" + r.id + "')"; }

}  // namespace

const MatchedFeature* FeatureMatch::find(const std::string& id) const {
  for (const auto& x : matched)
    if (x.feature->nominal.id == id) return &x;
  return nullptr;
}

FeatureMatch matchFeatureActuals(const std::vector<FeatureActual>& rows, const parts::PlanManifest& m) {
  FeatureMatch out;
  if (rows.empty()) return out;
  for (const auto& r : rows)
    if (r.cycle != rows.front().cycle)
      throw InputError(r.file, r.line, "cycle " + std::to_string(r.cycle) + ": the " + m.kind + " is measured once, but " +
                                           where(rows.front()) + " is of cycle (measurement run) " +
                                           std::to_string(rows.front().cycle) + ": give one run");
  std::map<std::string, const FeatureActual*> taken;  // manifest id -> row
  bool any_label = false, any_geometry = false;
  auto claim = [&](const FeatureActual& r, const parts::ManifestFeature& f, bool by_id) {
    const auto it = taken.find(f.nominal.id);
    if (it != taken.end())
      throw InputError(r.file, r.line, "feature " + f.nominal.id + " is given twice: by " + where(*it->second) + " and " + where(r));
    taken[f.nominal.id] = &r;
    out.matched.push_back({r, &f, by_id});
    (by_id ? any_label : any_geometry) = true;
  };
  for (const auto& r : rows) {
    if (r.kind == "point" || r.kind == "line" || r.kind == "other") {
      ++out.other_kinds;
      continue;
    }
    if (!r.has_geometry) {  // a QIF/DMIS feature with neither points nor measured geometry
      out.unmatched.push_back({r, "", 0, "states no measured geometry"});
      continue;
    }
    if (const auto* f = m.feature(r.id)) {
      if (!compatible(r.kind, f->nominal.kind))
        throw InputError(r.file, r.line, "'" + r.id + "' is a " + f->nominal.kind + " in the plan " + m.file + ", but the file gives a " +
                                             r.kind);
      // The features routes place the plan's points on the stated feature in the part frame: a
      // row named for a feature but far from it is a mislabelled row or a file in another frame.
      const Fit x = fitTo(r, f->nominal);
      if (!x.fits())
        throw InputError(r.file, r.line, r.kind + " '" + r.id + "' is named for " + f->nominal.id + " but lies off its nominal geometry: " +
                                             x.why + ". Mislabelled, or the file is not in the part frame (feature files are read in "
                                             "the part frame, docs/formats.md#feature-actuals-csv)");
      claim(r, *f, true);
      continue;
    }
    struct Candidate {
      const parts::ManifestFeature* f;
      double d;
    };
    std::vector<Candidate> fits;
    UnmatchedFeature nearest{r, "", std::numeric_limits<double>::infinity(), ""};
    for (const auto& f : m.features) {
      if (!compatible(r.kind, f.nominal.kind)) continue;
      const Fit x = fitTo(r, f.nominal);
      if (x.fits()) fits.push_back({&f, x.away_mm});
      if (x.away_mm < nearest.distance_mm) nearest.nearest = f.nominal.id, nearest.distance_mm = x.away_mm, nearest.why = x.why;
    }
    if (fits.empty()) {
      out.unmatched.push_back(nearest);
      continue;
    }
    std::sort(fits.begin(), fits.end(), [](const Candidate& a, const Candidate& b) { return a.d < b.d; });
    if (fits.size() > 1 && fits[1].d - fits[0].d < kAmbiguityMm)
      throw InputError(r.file, r.line, r.kind + " '" + r.id + "' fits both " + fits[0].f->nominal.id + " (" + formatSignificant4(fits[0].d) +
                                           " mm) and " + fits[1].f->nominal.id + " (" + formatSignificant4(fits[1].d) +
                                           " mm) by its nominal geometry: name it by its id");
    claim(r, *fits[0].f, false);
  }
  if (out.matched.empty() && !out.unmatched.empty()) {
    const auto& u = out.unmatched.front();
    throw InputError(u.actual.file, u.actual.line,
                     "no feature of the file fits a feature of the plan " + m.file + " by its id or its nominal geometry (" +
                         u.actual.kind + " '" + u.actual.id + "': nearest " + (u.nearest.empty() ? "none" : u.nearest) +
                         (u.nearest.empty() ? "" : ", " + formatSignificant4(u.distance_mm) + " mm") +
                         "): is the file in another frame? Features with foreign names are matched in the part frame "
                         "(docs/formats.md#feature-actuals-csv)");
  }
  out.assigned_by = any_label && any_geometry ? "labels and nominal geometry" : any_geometry ? "nominal geometry" : "labels";
  return out;
}

}  // namespace probeloop::evaluate
