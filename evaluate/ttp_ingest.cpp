#include "evaluate/ttp_ingest.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "core/csv.hpp"
#include "core/input_file.hpp"
#include "core/error.hpp"
#include "evaluate/feature_actuals.hpp"
#include "evaluate/feature_match.hpp"
#include "interop/dmis.hpp"
#include "interop/qif.hpp"
#include "core/units.hpp"
#include "gcode/probe_log.hpp"
#include "parts/machine.hpp"

namespace probeloop::evaluate {

using Eigen::Vector3d;

const char* ttpRouteName(TtpRoute r) {
  switch (r) {
    case TtpRoute::Cmm: return "cmm";
    case TtpRoute::OnMachine: return "on_machine";
    case TtpRoute::Gauge: return "gauge";
  }
  return "cmm";
}

namespace {

// Largest point number a file may give (a feature has tens of points; the bound keeps the
// conversion to int defined).
constexpr int kMaxPointNumber = 1000000;

// ".csv" at the end of the path, in any case.
bool csvExtension(const std::string& path) {
  static const std::string ext = ".csv";
  return path.size() >= ext.size() && std::equal(ext.begin(), ext.end(), path.end() - static_cast<std::ptrdiff_t>(ext.size()),
                                                 [](char e, char c) { return std::tolower(static_cast<unsigned char>(c)) == e; });
}

// The first non-comment, non-blank line.
std::string firstDataLine(const std::string& text) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // UTF-8 byte-order mark
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto a = line.find_first_not_of(" \t");
    if (a == std::string::npos || line[a] == '#') continue;
    return line.substr(a);
  }
  return "";
}


bool has(const std::vector<std::string>& h, const std::string& name) {
  return std::find(h.begin(), h.end(), name) != h.end();
}

std::string idList(const parts::PlanManifest& m) {
  std::string s;
  int n = 0;
  for (const auto& f : m.features) {
    if (n == 6) return s + ", ...";
    s += (n++ ? ", " : "") + f.nominal.id;
  }
  return s;
}

// Distance of p from a nominal feature: the normal distance, whether p lies inside the
// feature's extent + margin, and the 3D distance from the bounded patch (for messages).
struct Proximity {
  double normal_mm = std::numeric_limits<double>::infinity();
  bool inside = false;
  double patch_mm = std::numeric_limits<double>::infinity();
};

Proximity proximity(const parts::NominalFeature& f, const Vector3d& p, double margin) {
  Proximity r;
  const Vector3d w = p - f.point_mm;
  if (f.kind == "plane") {
    const double dn = f.direction.dot(w), du = f.u.dot(w), dv = f.v().dot(w);
    r.normal_mm = std::fabs(dn);
    r.inside = std::fabs(du) <= f.half_u_mm + margin && std::fabs(dv) <= f.half_v_mm + margin;
    const double eu = std::max(0.0, std::fabs(du) - f.half_u_mm), ev = std::max(0.0, std::fabs(dv) - f.half_v_mm);
    r.patch_mm = std::sqrt(dn * dn + eu * eu + ev * ev);
  } else if (f.kind == "cylinder") {
    const Vector3d a = f.direction.normalized();
    const double h = a.dot(w);
    const double dn = (w - h * a).norm() - f.radius_mm;
    r.normal_mm = std::fabs(dn);
    r.inside = std::fabs(h) <= f.half_v_mm + margin;
    const double eh = std::max(0.0, std::fabs(h) - f.half_v_mm);
    r.patch_mm = std::sqrt(dn * dn + eh * eh);
  } else if (f.kind == "sphere") {
    const double dn = w.norm() - f.radius_mm;
    r.normal_mm = std::fabs(dn);
    r.inside = true;
    r.patch_mm = std::fabs(dn);
  }
  return r;
}

}  // namespace

// The table's sense of turning: parts::turnedByTable (docs/conventions.md).
Vector3d machineToPartDirection(const parts::PlanManifest& m, const Vector3d& d, double c_deg) {
  const Eigen::Vector2d xy = parts::unturnedByTable(d.head<2>(), c_deg, m.c_positive_is_clockwise);
  return {xy.x(), xy.y(), d.z()};
}
Vector3d partToMachineDirection(const parts::PlanManifest& m, const Vector3d& d, double c_deg) {
  const Eigen::Vector2d xy = parts::turnedByTable(d.head<2>(), c_deg, m.c_positive_is_clockwise);
  return {xy.x(), xy.y(), d.z()};
}
Vector3d machineToPart(const parts::PlanManifest& m, const Vector3d& p, double c_deg) {
  const Vector3d c3(m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y(), 0.0);
  return machineToPartDirection(m, p - c3, c_deg) + c3 - m.part_origin_mm;
}
Vector3d partToMachine(const parts::PlanManifest& m, const Vector3d& p, double c_deg) {
  const Vector3d c3(m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y(), 0.0);
  return partToMachineDirection(m, p + m.part_origin_mm - c3, c_deg) + c3;
}

std::string detectTtpFormat(const std::string& path, const std::string& text) {
  if (interop::looksLikeQif(text)) return "qif";
  if (interop::looksLikeDmis(text)) return "dmis";
  const std::string first = firstDataLine(text);
  const bool csv = first.find(',') != std::string::npos || first.find(';') != std::string::npos || csvExtension(path);
  if (!csv) {  // a PT log: LinuxCNC LOG and Fanuc DPRNT lines parse alike
    const std::string kind = describeContent(text);
    if (!kind.empty() && kind.find("probe log") == std::string::npos)
      throw InputError(path, 0, "this is " + kind + "; a test piece is evaluated from a CMM export (CSV, QIF 3.0 Results, "
                                "DMIS output), the on-machine probe log (PT lines), a points CSV or dial-gauge readings");
    return "log";
  }
  const auto h = csvHeaderFields(text);
  if (looksLikeFeatureActuals(text)) return "features";
  if (has(h, "g_um")) return "gauge";
  if (has(h, "c_deg") || has(h, "time_s")) return "csv";
  return "cmm";
}

std::vector<std::string> assignByNominalGeometry(const std::vector<Vector3d>& pts, const std::vector<int>& lines,
                                                 const parts::PlanManifest& m, const std::string& file,
                                                 const TtpAssignmentRules& rules) {
  std::vector<std::string> out(pts.size());
  struct Problem {
    std::size_t index;
    std::string message;
  };
  std::vector<Problem> problems;
  std::size_t unassigned = 0;
  std::string example;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    struct Cand {
      const parts::NominalFeature* f;
      double d;
    };
    std::vector<Cand> cands;
    const parts::NominalFeature* nearest = nullptr;
    double nearest_d = std::numeric_limits<double>::infinity();
    for (const auto& mf : m.features) {
      const auto pr = proximity(mf.nominal, pts[i], rules.extent_margin_mm);
      if (pr.patch_mm < nearest_d) nearest_d = pr.patch_mm, nearest = &mf.nominal;
      if (pr.inside && pr.normal_mm <= rules.normal_tolerance_mm) cands.push_back({&mf.nominal, pr.normal_mm});
    }
    std::sort(cands.begin(), cands.end(), [](const Cand& a, const Cand& b) { return a.d < b.d; });
    if (cands.empty()) {
      ++unassigned;
      std::string msg = "the point (" + formatNumber(pts[i].x(), 4) + ", " + formatNumber(pts[i].y(), 4) + ", " +
                        formatNumber(pts[i].z(), 4) + ") mm fits no nominal feature within " +
                        formatNumber(rules.normal_tolerance_mm) + " mm";
      if (nearest)
        msg += "; the nearest is " + nearest->id + " at " + formatNumber(nearest_d, 3) + " mm";
      if (example.empty())
        example = "line " + std::to_string(lines[i]) + (nearest ? ": nearest " + nearest->id + " at " + formatNumber(nearest_d, 3) + " mm" : "");
      problems.push_back({i, msg});
      continue;
    }
    if (cands.size() >= 2 && cands[1].d - cands[0].d < rules.ambiguity_mm) {
      problems.push_back({i, "the point is ambiguous: it lies " + formatNumber(cands[0].d, 3) + " mm from " + cands[0].f->id +
                                 " and " + formatNumber(cands[1].d, 3) + " mm from " + cands[1].f->id +
                                 " (closer than " + formatNumber(rules.ambiguity_mm) +
                                 " mm to each other, e.g. at a shared edge); move it onto one face or label it in a 'feature' column"});
      continue;
    }
    out[i] = cands[0].f->id;
  }
  if (!pts.empty() && 2 * unassigned > pts.size())
    throw InputError(file, 0,
                     std::to_string(unassigned) + " of " + std::to_string(pts.size()) +
                         " points fit no nominal feature of the manifest (" + example +
                         "): the file is probably not in the part frame (seed 004 L2055: the top plane gives Z and "
                         "its origin, the flanks of the large notch the X direction, the centre of the circle on the "
                         "datum band the X/Y origin). Export the points in the part alignment, or keep the manifest's "
                         "feature ids in a 'feature' column (labelled points are aligned by the datums in any frame)");
  if (!problems.empty()) throw InputError(file, lines[problems.front().index], problems.front().message);
  return out;
}

namespace {

// One point of a CMM export, whatever the file: its label (feature), its number within the
// feature (0: none), its line.
struct CmmRawPoint {
  std::string label;
  int point = 0;
  int line = 0;
  Vector3d p;
};

// Labels that are all manifest ids are used; none of ours -> the nominal geometry; a mix is
// refused. Point numbers: the file's with labels, else the order of appearance per feature.
TtpPoints cmmPointsFromRows(const std::string& path, const std::string& format, const std::vector<CmmRawPoint>& rows,
                            bool labelled, const parts::PlanManifest& m) {
  TtpPoints out;
  out.file = path;
  out.format = format;
  out.route = TtpRoute::Cmm;
  if (rows.empty()) throw InputError(path, 0, "no points");
  std::vector<Vector3d> pts;
  std::vector<int> lines;
  for (const auto& r : rows) {
    pts.push_back(r.p);
    lines.push_back(r.line);
  }
  std::size_t ours = 0, first_foreign = rows.size();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (m.feature(rows[i].label))
      ++ours;
    else if (first_foreign == rows.size())
      first_foreign = i;
  }
  std::vector<std::string> feature;
  if (labelled && ours == rows.size()) {
    for (const auto& r : rows) feature.push_back(r.label);
    out.assigned_by = "labels";
  } else if (labelled && ours > 0) {
    throw InputError(path, lines[first_foreign],
                     "feature '" + rows[first_foreign].label + "' is not a feature of the manifest " + m.file + " (" + idList(m) +
                         "), but other " + (format == "qif" ? "features" : "lines") +
                         " use the manifest's ids: label every point with the manifest's ids, or none "
                         "(points are then assigned by the nominal geometry)");
  } else {
    feature = assignByNominalGeometry(pts, lines, m, path);
    out.assigned_by = "nominal geometry";
  }
  std::map<std::string, int> count;
  std::map<std::pair<std::string, int>, int> seen;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    TtpPoint p;
    p.feature = feature[i];
    p.line = lines[i];
    p.p_mm = pts[i];
    const int nth = ++count[p.feature];
    p.point = rows[i].point > 0 && out.assigned_by == "labels" ? rows[i].point : nth;
    const auto key = std::make_pair(p.feature, p.point);
    if (seen.count(key))
      throw InputError(path, p.line, "feature " + p.feature + " point " + std::to_string(p.point) + " appears twice (lines " +
                                         std::to_string(seen[key]) + " and " + std::to_string(p.line) + ")");
    seen[key] = p.line;
    out.points.push_back(p);
  }
  return out;
}

// Why the piece's evaluation cannot do without a feature's points ("" when it can: the values
// that use it are listed as not evaluated). The thermal test piece: its datums (the part frame)
// and its reference features (cycle 0: every value of a side is measured against them); the
// stepped workpiece: every planned plane.
std::string neededBecause(const parts::PlanManifest& m, const parts::ManifestFeature& f) {
  const std::string& id = f.nominal.id;
  if (m.pieceKind() == parts::PieceKind::SteppedWorkpiece)
    return "the stepped workpiece's evaluation needs the points of every planned plane, " + id + "'s too";
  if (m.pieceKind() != parts::PieceKind::ThermalTestPiece) return "";
  if (f.nominal.role.rfind("datum", 0) == 0) return "the datum " + id + " needs its points (seed 004 L2055: the part frame)";
  if (f.cycle == 0)
    return "the reference feature " + id + " (cycle 0) needs its points: every value of its side is measured against it";
  return "";
}

// A feature a QIF/DMIS file states with its measured geometry but without points, in a file whose
// other features carry points (issue 34): the point route fits its own features, so it is not used.
// Said as a warning with its line; refused, with its line and the reason, when the evaluation
// needs that feature's points and the file gives none for it. Not a producer's form mistake (the
// file's meaning is whole): --strict keeps it a warning. Foreign names are matched to the plan by
// the stated geometry (feature_match.hpp) to say which feature it is.
void statedWithoutPoints(const interop::CmmDocument& d, const parts::PlanManifest& m, const TtpPoints& points,
                         std::vector<InputWarning>& warnings) {
  interop::CmmDocument stated;  // those features alone (not a copy of every point)
  stated.file = d.file;
  std::size_t with_points = 0;
  for (const auto& f : d.features) {
    if (!f.points.empty()) ++with_points;
    else if (f.measured.given) stated.features.push_back(f);
  }
  if (stated.features.empty()) return;
  std::vector<FeatureActual> rows;
  try {
    rows = featureActualsFromCmm(stated);
  } catch (const InputError&) {
    // Not plausible as stated: named by the file's names alone below.
  }
  std::map<int, std::string> manifest_id;  // by line: the plan's feature it states
  for (const auto& f : stated.features)
    if (m.feature(f.name)) manifest_id[f.line] = f.name;
  if (manifest_id.size() < stated.features.size() && !rows.empty()) {
    try {
      for (const auto& x : matchFeatureActuals(rows, m).matched)
        if (!x.by_id) manifest_id[x.actual.line] = x.feature->nominal.id;
    } catch (const InputError&) {
      // Not matched (another frame, ambiguous): named by the file's names alone.
    }
  }
  std::set<std::string> measured;
  for (const auto& p : points.points) measured.insert(p.feature);
  const std::string others = std::to_string(with_points) + (with_points == 1 ? " feature" : " features") + " of the file carry points";
  const std::string route = "the point route fits its own features from the points (a file of features only is evaluated from "
                            "them, docs/formats.md#evaluating-from-features)";
  for (const auto& f : stated.features) {
    const auto it = manifest_id.find(f.line);
    const std::string id = it == manifest_id.end() ? "" : it->second;
    const std::string name = "feature " + f.name + (id.empty() || id == f.name ? "" : " (" + id + " by its nominal geometry)");
    const std::string what = name + " states its measured geometry but no points, while " + others;
    const auto* mf = id.empty() ? nullptr : m.feature(id);
    const std::string need = mf && !measured.count(id) ? neededBecause(m, *mf) : "";
    if (!need.empty())
      throw InputError(d.file, f.line, what + ": " + need + ", and " + route + ": export " + f.name + "'s points, or no feature's");
    warnings.push_back({d.file, f.line, what + ": not used; " + route, false});
  }
}

// A QIF 3.0 Results document or a DMIS output file: every measured feature's points, labelled
// by its name, numbered in their order (the line: the feature measurement's).
TtpPoints cmmResults(const std::string& path, const std::string& text, const parts::PlanManifest& m, bool qif, bool strict) {
  const interop::CmmReadOptions options{strict};
  const auto d = qif ? interop::parseQifResults(text, path, options) : interop::parseDmisOutput(text, path, options);
  if (d.runs > 1)
    throw InputError(path, 0, std::to_string(d.runs) + " MeasurementResults (runs) in one file: evaluate reads one part's "
                                                      "measurement; write each run to its own file");
  std::vector<CmmRawPoint> rows;
  for (const auto& f : d.features) {
    int k = 0;
    for (const auto& p : f.points) rows.push_back({f.name, ++k, f.line, p.p_mm});
  }
  if (rows.empty())
    throw InputError(path, 0, std::string("no measured points (") + (qif ? "MeasuredPointSets" : "FA(<feature>_Pnn)=FEAT/POINT") + ") in " +
                                  std::to_string(d.features.size()) +
                                  " measured features: the evaluation fits its own planes and needs the points");
  auto out = cmmPointsFromRows(path, qif ? "qif" : "dmis", rows, true, m);
  out.warnings = inputWarnings(d);
  statedWithoutPoints(d, m, out, out.warnings);
  return out;
}

}  // namespace

TtpPoints readTtpCmmExport(const std::string& path, const std::string& text, const parts::PlanManifest& m, bool strict) {
  if (interop::looksLikeQif(text)) return cmmResults(path, text, m, true, strict);
  if (interop::looksLikeDmis(text)) return cmmResults(path, text, m, false, strict);
  const CsvTable t = parseCsv(text, path);
  auto col = [&](const char* a, const char* b) {
    const int c = t.column(a);
    return c >= 0 ? c : t.column(b);
  };
  const int cx = col("x_mm", "x"), cy = col("y_mm", "y"), cz = col("z_mm", "z");
  if (cx < 0 || cy < 0 || cz < 0)
    throw InputError(path, t.header_line,
                     "a CMM export needs the columns x_mm,y_mm,z_mm (or x,y,z) and optionally feature, point, nx,ny,nz");
  const int cf = t.column("feature"), cp = t.column("point");
  std::vector<CmmRawPoint> rows;
  for (const auto& row : t.rows) {
    CmmRawPoint r;
    r.p = Vector3d(t.number(row, cx), t.number(row, cy), t.number(row, cz));
    r.line = row.line;
    r.label = cf >= 0 ? row.fields[static_cast<std::size_t>(cf)] : "";
    rows.push_back(r);
  }
  auto out = cmmPointsFromRows(path, "cmm", rows, cf >= 0, m);
  // The file's point numbers count only where its labels are ours (else: order of appearance).
  if (cp >= 0 && out.assigned_by == "labels") {
    std::map<std::pair<std::string, int>, int> seen;
    for (std::size_t i = 0; i < out.points.size(); ++i) {
      auto& p = out.points[i];
      const double k = t.number(t.rows[i], cp);
      // Bounded before the conversion to int (7e61 was undefined behaviour: fuzz/ttp_cmm_csv).
      if (k != std::round(k) || k < 1 || k > kMaxPointNumber)
        throw InputError(path, p.line, "point must be a positive integer up to " + std::to_string(kMaxPointNumber));
      p.point = static_cast<int>(k);
      const auto key = std::make_pair(p.feature, p.point);
      if (seen.count(key))
        throw InputError(path, p.line, "feature " + p.feature + " point " + std::to_string(p.point) + " appears twice (lines " +
                                           std::to_string(seen[key]) + " and " + std::to_string(p.line) + ")");
      seen[key] = p.line;
    }
  }
  return out;
}

TtpPoints readTtpOnMachine(const std::string& path, const std::string& text, const std::string& format,
                           const parts::PlanManifest& m) {
  struct Raw {
    int line, position = 0, point;
    std::string feature;  // when the CSV names it
    Vector3d tip;
    double c_deg = NAN;
    Vector3d approach = Vector3d::Constant(NAN);
  };
  std::vector<Raw> raw;
  TtpPoints out;
  out.file = path;
  out.format = format;
  out.route = TtpRoute::OnMachine;
  out.assigned_by = "manifest positions";
  if (format == "csv") {
    const CsvTable t = parseCsv(text, path);
    const char* need[] = {"feature", "point", "x_mm", "y_mm", "z_mm"};
    for (const char* n : need)
      if (t.column(n) < 0)
        throw InputError(path, t.header_line, std::string("missing column '") + n +
                                                  "'; the on-machine points CSV is time_s,cycle,c_deg,feature,point,x_mm,y_mm,z_mm,nx,ny,nz");
    const int cf = t.column("feature"), cp = t.column("point"), cx = t.column("x_mm"), cy = t.column("y_mm"),
              cz = t.column("z_mm"), cc = t.column("c_deg"), cnx = t.column("nx"), cny = t.column("ny"), cnz = t.column("nz");
    for (const auto& row : t.rows) {
      Raw r;
      r.line = row.line;
      const std::string& f = row.fields[static_cast<std::size_t>(cf)];
      if (f.size() > 1 && (f[0] == 'P' || f[0] == 'S') && f.find_first_not_of("0123456789", 1) == std::string::npos) {
        r.position = std::stoi(f.substr(1));
      } else if (m.feature(f)) {
        r.feature = f;
      } else {
        throw InputError(path, row.line, "feature '" + f + "': expected P<position> or a feature id of the manifest " + m.file);
      }
      const double k = t.number(row, cp);
      if (k != std::round(k) || k < 1 || k > kMaxPointNumber)
        throw InputError(path, row.line, "point must be a positive integer up to " + std::to_string(kMaxPointNumber));
      r.point = static_cast<int>(k);
      r.tip = Vector3d(t.number(row, cx), t.number(row, cy), t.number(row, cz));
      if (cc >= 0) r.c_deg = t.number(row, cc);
      if (cnx >= 0 && cny >= 0 && cnz >= 0) r.approach = Vector3d(t.number(row, cnx), t.number(row, cny), t.number(row, cnz));
      raw.push_back(r);
    }
  } else {
    for (const auto& p : gcode::parseProbeLog(text, path)) {
      Raw r;
      r.line = p.line;
      r.position = p.position;
      r.point = p.point;
      r.tip = p.tip_mm;
      raw.push_back(r);
    }
  }
  if (raw.empty()) throw InputError(path, 0, "no probed points");
  // Manifest points by (feature, point).
  std::map<std::pair<std::string, int>, const parts::ManifestPoint*> planned;
  for (const auto& p : m.points) planned[{p.feature, p.point}] = &p;
  std::map<std::pair<std::string, int>, int> seen;
  for (const auto& r : raw) {
    std::string id = r.feature;
    if (id.empty()) {
      const auto* f = m.featureAtPosition(r.position);
      if (!f)
        throw InputError(path, r.line, "position " + std::to_string(r.position) + " is not a probed feature of the manifest " +
                                           m.file + " (the log belongs to another plan?)");
      id = f->nominal.id;
    }
    const auto it = planned.find({id, r.point});
    if (it == planned.end())
      throw InputError(path, r.line, "feature " + id + " point " + std::to_string(r.point) + " is not planned in the manifest " + m.file);
    const auto& pp = *it->second;
    if (!(pp.approach.norm() > 0))
      throw InputError(m.file, 0, "feature " + id + " point " + std::to_string(r.point) + " has no approach direction in the manifest");
    const auto key = std::make_pair(id, r.point);
    if (seen.count(key))
      throw InputError(path, r.line, "feature " + id + " point " + std::to_string(r.point) + " appears twice (lines " +
                                         std::to_string(seen[key]) + " and " + std::to_string(r.line) +
                                         "): one inspection per file");
    seen[key] = r.line;
    if (std::isfinite(r.c_deg)) {
      const double dc = std::remainder(r.c_deg - pp.c_deg, 360.0);
      if (std::fabs(dc) > 1e-3)
        throw InputError(path, r.line, "c_deg " + formatNumber(r.c_deg) + " of feature " + id + " point " + std::to_string(r.point) +
                                           ": the manifest plans C = " + formatNumber(pp.c_deg) + " deg");
    }
    if (r.approach.allFinite() && r.approach.norm() > 0 && (r.approach.normalized() - pp.approach.normalized()).norm() > 1e-2)
      throw InputError(path, r.line, "the approach of feature " + id + " point " + std::to_string(r.point) +
                                         " differs from the manifest's (" + formatNumber(pp.approach.x(), 4) + ", " +
                                         formatNumber(pp.approach.y(), 4) + ", " + formatNumber(pp.approach.z(), 4) + ")");
    const double off = (r.tip - pp.contact_mm).norm();
    if (off > 10.0)
      throw InputError(path, r.line, "feature " + id + " point " + std::to_string(r.point) + " is " + formatNumber(off, 3) +
                                         " mm from its planned contact: the log does not match the manifest " + m.file);
    TtpPoint p;
    p.feature = id;
    p.point = r.point;
    p.line = r.line;
    const Vector3d surface = r.tip + m.tip_radius_mm * pp.approach.normalized();  // planes probed square
    p.p_mm = machineToPart(m, surface, pp.c_deg);
    out.points.push_back(p);
  }
  return out;
}

TtpGaugeReadings readTtpGauge(const std::string& path, const std::string& text, const parts::PlanManifest& m) {
  const CsvTable t = parseCsv(text, path);
  const int cf = t.column("facet"), cg = t.column("g_um");
  if (cf < 0 || cg < 0)
    throw InputError(path, t.header_line, "a dial-gauge file needs the columns facet,g_um (seed 004 Eqs. 7.7-7.9)");
  TtpGaugeReadings out;
  out.file = path;
  std::map<std::string, int> seen;
  for (const auto& row : t.rows) {
    TtpGaugeReading r;
    r.line = row.line;
    r.facet = row.fields[static_cast<std::size_t>(cf)];
    const auto* f = m.feature(r.facet);
    if (!f || f->nominal.role != "facet")
      throw InputError(path, row.line, "'" + r.facet + "' is not a facet of the manifest " + m.file + " (X1_1 ... Y2_" +
                                           std::to_string(m.ttp.facets_per_segment) + ")");
    if (seen.count(r.facet))
      throw InputError(path, row.line, "facet " + r.facet + " is listed twice (lines " + std::to_string(seen[r.facet]) + " and " +
                                           std::to_string(row.line) + ")");
    seen[r.facet] = row.line;
    r.g_um = t.number(row, cg);
    out.readings.push_back(r);
  }
  if (out.readings.empty()) throw InputError(path, 0, "no gauge readings");
  return out;
}

}  // namespace probeloop::evaluate
