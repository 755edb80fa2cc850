#include "evaluate/feature_actuals.hpp"

#include <algorithm>
#include <cmath>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "geometry/fit.hpp"
#include "interop/dmis.hpp"
#include "interop/qif.hpp"

namespace probeloop::evaluate {

namespace {

const char* kRequired[] = {"cycle", "id", "kind", "x_mm", "y_mm", "z_mm", "i", "j", "k", "size_mm", "form_um", "n_points"};
const char* kKinds[] = {"sphere", "circle", "cylinder", "plane", "point"};

bool blank(const CsvRow& r, int c) { return c < 0 || c >= static_cast<int>(r.fields.size()) || r.fields[c].empty(); }

std::string line(const FeatureActual& f) { return std::to_string(f.line); }

// A measurement of a machined part: beyond 1 km (mm fields) or 1 m (um fields) it is a broken
// file, and squared in a budget it would overflow to inf.
void checkPlausible(const FeatureActual& f) {
  constexpr double kMaxMm = 1e6, kMaxUm = 1e6;
  auto fail = [&](const std::string& field, double v, const char* unit, double max) {
    throw InputError(f.file, f.line, field + ": " + formatNumber(v) + " " + unit + " is not a plausible measurement (at most " +
                                         formatNumber(max) + " " + unit + ")");
  };
  const char* xyz[3] = {"x_mm", "y_mm", "z_mm"};
  for (int a = 0; a < 3; ++a)
    if (std::fabs(f.location_mm(a)) > kMaxMm) fail(xyz[a], f.location_mm(a), "mm", kMaxMm);
  if (std::isfinite(f.size_mm) && f.size_mm > kMaxMm) fail("size_mm", f.size_mm, "mm", kMaxMm);
  if (std::isfinite(f.form_um) && f.form_um > kMaxUm) fail("form_um", f.form_um, "um", kMaxUm);
  if (f.u_um && f.u_um->maxCoeff() > kMaxUm) fail("u_x_um,u_y_um,u_z_um", f.u_um->maxCoeff(), "um", kMaxUm);
}

}  // namespace

int minimumPoints(const std::string& kind) {
  // The parameters a least-squares fit determines: a plane's position and normal (3), a
  // circle's centre in its plane and radius (3), a sphere's centre and radius (4), a cylinder's
  // axis (4) and radius (5); a point is one point.
  if (kind == "plane" || kind == "circle") return 3;
  if (kind == "sphere") return 4;
  if (kind == "cylinder") return 5;
  return 1;
}

bool looksLikeFeatureActuals(const std::string& text) {
  const auto h = csvHeaderFields(text);
  for (const char* c : kRequired)
    if (std::find(h.begin(), h.end(), c) == h.end()) return false;
  return true;
}

std::vector<FeatureActual> parseFeatureActuals(const std::string& text, const std::string& file, int max_cycle) {
  const CsvTable t = parseCsv(text, file);
  int col[12];
  for (int i = 0; i < 12; ++i) {
    col[i] = t.column(kRequired[i]);
    if (col[i] < 0)
      throw InputError(file, t.header_line, std::string("missing column '") + kRequired[i] +
                                                "'; feature actuals need cycle,id,kind,x_mm,y_mm,z_mm,i,j,k,size_mm,form_um,n_points "
                                                "(docs/formats.md#feature-actuals-csv)");
  }
  const int cu[3] = {t.column("u_x_um"), t.column("u_y_um"), t.column("u_z_um")};
  const int n_u = (cu[0] >= 0) + (cu[1] >= 0) + (cu[2] >= 0);
  if (n_u != 0 && n_u != 3)
    throw InputError(file, t.header_line, "the stated uncertainty needs all three columns u_x_um,u_y_um,u_z_um or none");
  const int c_time = t.column("time_s"), c_alg = t.column("algorithm");
  std::vector<FeatureActual> out;
  for (const auto& row : t.rows) {
    FeatureActual f;
    f.file = file;
    f.line = row.line;
    auto fail = [&](const std::string& field, const std::string& why) { throw InputError(file, row.line, field + ": " + why); };
    const double cyc = t.number(row, col[0]);
    if (cyc != std::round(cyc) || cyc < 1) fail("cycle", row.fields[col[0]] + " is not a positive integer");
    if (max_cycle > 0 && cyc > max_cycle) fail("cycle", row.fields[col[0]] + " is beyond the plan's " + std::to_string(max_cycle) + " cycles");
    if (cyc > 1e6) fail("cycle", row.fields[col[0]] + " is not a plausible cycle number");
    f.cycle = static_cast<int>(cyc);
    f.id = row.fields[col[1]];
    if (f.id.empty()) fail("id", "empty");
    f.kind = row.fields[col[2]];
    std::transform(f.kind.begin(), f.kind.end(), f.kind.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (std::find(std::begin(kKinds), std::end(kKinds), f.kind) == std::end(kKinds))
      fail("kind", "'" + row.fields[col[2]] + "' is not a feature kind: expected sphere, circle, cylinder, plane or point");
    f.location_mm = {t.number(row, col[3]), t.number(row, col[4]), t.number(row, col[5])};
    const bool directed = f.kind == "circle" || f.kind == "cylinder" || f.kind == "plane";
    if (directed || !(blank(row, col[6]) && blank(row, col[7]) && blank(row, col[8]))) {
      const Eigen::Vector3d d(t.number(row, col[6]), t.number(row, col[7]), t.number(row, col[8]));
      if (directed && !(d.norm() > 1e-9)) fail("i,j,k", "a " + f.kind + " needs its axis or normal (zero length)");
      if (directed) f.direction = d.normalized();
    }
    const bool sized = f.kind == "sphere" || f.kind == "circle" || f.kind == "cylinder";
    f.size_mm = NAN;
    if (sized || !blank(row, col[9])) {
      f.size_mm = t.number(row, col[9]);
      if (!(f.size_mm > 0)) fail("size_mm", row.fields[col[9]] + ": a diameter must be positive");
    }
    f.form_um = NAN;
    if (!blank(row, col[10])) {
      f.form_um = t.number(row, col[10]);
      if (f.form_um < 0) fail("form_um", row.fields[col[10]] + " is negative");
    }
    // Empty: not stated (0), as a QIF feature without its points; the planned count stands in.
    const double n = blank(row, col[11]) ? 0.0 : t.number(row, col[11]);
    if (n != std::round(n) || n < 0 || n > 1e9 || (n == 0 && !blank(row, col[11])))
      fail("n_points", row.fields[col[11]] + " is not a positive integer (leave it empty when the report does not state it)");
    f.n_points = static_cast<int>(n);
    // Fewer points than the element's parameters fix no element: the row is not a fit.
    if (f.n_points > 0 && f.n_points < minimumPoints(f.kind))
      fail("n_points", row.fields[col[11]] + " points fit no " + f.kind + ": a " + f.kind + " has " + std::to_string(minimumPoints(f.kind)) +
                           " parameters, so its fit needs at least " + std::to_string(minimumPoints(f.kind)) + " points");
    const int n_blank = n_u == 3 ? blank(row, cu[0]) + blank(row, cu[1]) + blank(row, cu[2]) : 3;
    if (n_blank != 0 && n_blank != 3) fail("u_x_um,u_y_um,u_z_um", "all three or none (this row's location has no stated u)");
    if (n_blank == 0) {
      Eigen::Vector3d u;
      for (int a = 0; a < 3; ++a) {
        u(a) = t.number(row, cu[a]);
        if (u(a) < 0) fail(t.header[cu[a]], row.fields[cu[a]] + " is negative");
      }
      f.u_um = u;
    }
    if (!blank(row, c_time)) f.time_s = t.number(row, c_time);
    if (!blank(row, c_alg)) f.algorithm = row.fields[static_cast<std::size_t>(c_alg)];
    checkPlausible(f);
    out.push_back(std::move(f));
  }
  if (out.empty()) throw InputError(file, t.header_line, "no features in the file: nothing to evaluate");
  return out;
}

std::vector<FeatureActual> featureActualsFromCmm(const interop::CmmDocument& d, int max_cycle, std::optional<double> known_radius_mm) {
  std::vector<FeatureActual> out;
  for (const auto& c : d.features) {
    FeatureActual f;
    f.file = d.file;
    f.line = c.line;
    f.cycle = std::max(c.run, 1);
    f.id = c.name;
    f.kind = interop::cmmFeatureKindName(c.kind);
    if (c.kind == interop::CmmFeatureKind::Sphere && !c.measured.given) {
      // Points only: the centre the CMM software would have stated, from them (issue 34 item 2).
      if (c.points.size() < 4)
        throw InputError(d.file, c.line, "sphere '" + c.name + "' has no measured Location and " + std::to_string(c.points.size()) +
                                             " points: a sphere's centre needs its Location or at least 4 points");
      geometry::Points3 p;
      for (const auto& q : c.points) p.push_back(q.p_mm);
      geometry::FitResult fit;
      geometry::FitOptions options;
      options.fixed_radius_mm = known_radius_mm;  // the point route's default (docs/uncertainty.md)
      try {
        fit = geometry::fitElement(geometry::ElementKind::Sphere, p, options).fit;
      } catch (const GeometryError& x) {
        throw InputError(d.file, c.line, "sphere '" + c.name + "' (points only): " + x.what());
      }
      f.fitted_here = true;
      if (known_radius_mm) f.fitted_known_radius_mm = *known_radius_mm;
      f.has_geometry = true;
      f.location_mm = fit.element.position_mm;
      f.size_mm = 2 * fit.element.radius_mm;
      f.form_um = fit.form_mm * 1e3;
      f.n_points = static_cast<int>(p.size());
      if (max_cycle > 0 && f.cycle > max_cycle)
        throw InputError(d.file, c.line, "measurement run " + std::to_string(f.cycle) + " (a cycle) is beyond the plan's " +
                                             std::to_string(max_cycle) + " cycles");
      checkPlausible(f);
      out.push_back(std::move(f));
      continue;
    }
    if (max_cycle > 0 && f.cycle > max_cycle)
      throw InputError(d.file, c.line, "measurement run " + std::to_string(f.cycle) + " (a cycle) is beyond the plan's " +
                                           std::to_string(max_cycle) + " cycles");
    f.has_geometry = c.measured.given;
    f.location_mm = c.measured.location_mm;
    f.direction = c.measured.direction;
    f.size_mm = c.measured.diameter_mm;
    f.form_um = c.measured.form_mm * 1e3;
    f.algorithm = c.measured.algorithm;
    f.n_points = static_cast<int>(std::min<std::size_t>(c.points.size(), 1000000000));
    if (f.has_geometry) checkPlausible(f);
    out.push_back(std::move(f));
  }
  if (out.empty()) throw InputError(d.file, 0, "no measured features in the file: nothing to evaluate");
  return out;
}

bool holdsOnlyFeatures(const interop::CmmDocument& d) {
  bool any_geometry = false;
  for (const auto& f : d.features) {
    if (!f.points.empty()) return false;
    any_geometry = any_geometry || f.measured.given;
  }
  return any_geometry;
}

std::optional<StatedFeatureFile> readStatedFeatures(const std::string& path, const std::string& text, bool strict) {
  StatedFeatureFile out;
  if (looksLikeFeatureActuals(text)) {
    out.format = "features";
    out.rows = parseFeatureActuals(text, path);
    return out;
  }
  const bool qif = interop::looksLikeQif(text);
  if (!qif && (!interop::looksLikeDmis(text) || interop::isDmisProgram(text))) return std::nullopt;
  const interop::CmmReadOptions options{strict};
  const auto d = qif ? interop::parseQifResults(text, path, options) : interop::parseDmisOutput(text, path, options);
  if (!holdsOnlyFeatures(d)) return std::nullopt;
  if (d.runs > 1)
    throw InputError(path, 0, std::to_string(d.runs) + " MeasurementResults (runs) in one file: the piece is measured once; write "
                                                      "each run to its own file");
  out.format = qif ? "qif" : "dmis";
  out.rows = featureActualsFromCmm(d);
  out.warnings = inputWarnings(d);
  return out;
}

SphereCentresFromFeatures sphereCentresFromFeatures(const std::vector<FeatureActual>& rows, const parts::PlanManifest& m) {
  constexpr double kNear_mm = 5.0, kDiameter_mm = 1.0;
  SphereCentresFromFeatures out;
  // The places: positions whose nominal centres coincide (a repeat) share one.
  std::vector<int> place_of(m.spheres.size());
  std::vector<std::vector<int>> places;
  for (std::size_t i = 0; i < m.spheres.size(); ++i) {
    std::size_t p = 0;
    while (p < places.size() &&
           (m.spheres[static_cast<std::size_t>(places[p][0] - 1)].nominal_centre_mm - m.spheres[i].nominal_centre_mm).norm() > 1e-6)
      ++p;
    if (p == places.size()) places.push_back({});
    places[p].push_back(m.spheres[i].position);
    place_of[i] = static_cast<int>(p);
  }
  std::map<int, std::map<std::size_t, std::vector<const FeatureActual*>>> foreign;  // cycle -> place -> rows
  auto claim = [&](const FeatureActual& f, int position, bool by_id) {
    auto& cyc = out.by_cycle[f.cycle];
    const auto it = cyc.find(position);
    if (it != cyc.end())
      throw InputError(f.file, f.line, "cycle " + std::to_string(f.cycle) + ": position " + std::to_string(position) +
                                           " is given twice, by the rows at lines " + line(it->second.feature) + " ('" +
                                           it->second.feature.id + "') and " + line(f) + " ('" + f.id + "')");
    cyc[position] = {f, position, by_id};
  };
  for (const auto& f : rows) {
    if (f.kind != "sphere") {
      ++out.other_kinds;
      continue;
    }
    if (std::isfinite(f.size_mm) && std::fabs(f.size_mm / 2 - m.sphere_radius_mm) > kDiameter_mm / 2)
      throw InputError(f.file, f.line, "size_mm: a diameter of " + formatNumber(f.size_mm) + " mm is not the artifact's sphere (" +
                                           formatNumber(2 * m.sphere_radius_mm) + " mm, within " + formatNumber(kDiameter_mm) + " mm)");
    const auto s = std::find_if(m.spheres.begin(), m.spheres.end(), [&](const auto& x) { return x.id == f.id; });
    if (s != m.spheres.end()) {
      claim(f, s->position, true);
      continue;
    }
    std::vector<std::size_t> near;
    double nearest = INFINITY;
    int nearest_pos = 0;
    for (std::size_t p = 0; p < places.size(); ++p) {
      const double d = (m.spheres[static_cast<std::size_t>(places[p][0] - 1)].nominal_centre_mm - f.location_mm).norm();
      if (d < nearest) nearest = d, nearest_pos = places[p][0];
      if (d <= kNear_mm) near.push_back(p);
    }
    if (near.empty())
      throw InputError(f.file, f.line, "sphere '" + f.id + "' is " + formatNumber(nearest, 3) + " mm from the nearest planned centre (S" +
                                           std::to_string(nearest_pos) + "); a foreign id needs its centre within " +
                                           formatNumber(kNear_mm) + " mm of one");
    if (near.size() > 1)
      throw InputError(f.file, f.line, "sphere '" + f.id + "' lies within " + formatNumber(kNear_mm) + " mm of both S" +
                                           std::to_string(places[near[0]][0]) + " and S" + std::to_string(places[near[1]][0]) +
                                           ": name it by its id");
    foreign[f.cycle][near[0]].push_back(&f);
  }
  // Not structured bindings: the lambda below uses fs, which clang before 16 cannot capture
  // (C++20 P1091; scripts/fuzz.sh builds with clang 14).
  for (auto& cycle_entry : foreign)
    for (auto& place_entry : cycle_entry.second) {
      const int cycle = cycle_entry.first;
      const std::size_t p = place_entry.first;
      auto& fs = place_entry.second;
      std::vector<int> free;
      for (int pos : places[p])
        if (!out.by_cycle[cycle].count(pos)) free.push_back(pos);
      auto both = [&](std::size_t a, std::size_t b) {
        return "the rows at lines " + line(*fs[a]) + " ('" + fs[a]->id + "') and " + line(*fs[b]) + " ('" + fs[b]->id + "')";
      };
      if (fs.size() > free.size()) {
        if (free.empty()) {
          const auto& named = out.by_cycle[cycle].at(places[p][0]).feature;
          throw InputError(fs[0]->file, fs[0]->line, "cycle " + std::to_string(cycle) + ": sphere '" + fs[0]->id + "' matches S" +
                                                         std::to_string(places[p][0]) + ", which the row at line " + line(named) +
                                                         " ('" + named.id + "') names by its id");
        }
        throw InputError(fs[1]->file, fs[1]->line, "cycle " + std::to_string(cycle) + ": " + both(0, 1) + " both match S" +
                                                       std::to_string(free[0]) + " by their centres: name them by their ids");
      }
      if (free.size() > 1) {  // a repeat: the same place at several times of the cycle
        const auto& f = *fs[0];
        if (fs.size() < free.size() || std::any_of(fs.begin(), fs.end(), [](const FeatureActual* x) { return !x->time_s; }))
          throw InputError(f.file, f.line, "cycle " + std::to_string(cycle) + ": " + (fs.size() > 1 ? both(0, 1) + " both match S" : "sphere '" + f.id + "' matches S") +
                                               std::to_string(free[0]) + " and S" + std::to_string(free[1]) +
                                               " (the same place, probed twice): give the ids or time_s for each");
        std::stable_sort(fs.begin(), fs.end(), [](const FeatureActual* a, const FeatureActual* b) { return *a->time_s < *b->time_s; });
        for (std::size_t i = 1; i < fs.size(); ++i)
          if (*fs[i]->time_s == *fs[i - 1]->time_s)
            throw InputError(fs[i]->file, fs[i]->line, "cycle " + std::to_string(cycle) + ": " + both(i - 1, i) +
                                                           " match the same place at the same time_s: name them by their ids");
      }
      for (std::size_t i = 0; i < fs.size(); ++i) claim(*fs[i], free[i], false);
    }
  return out;
}

}  // namespace probeloop::evaluate
