#include "evaluate/sw_features.hpp"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/input_file.hpp"
#include "evaluate/feature_match.hpp"
#include "evaluate/feature_points.hpp"

namespace probeloop::evaluate {

namespace {

// Which values of the evaluation need a plane (for the refusal of a missing one).
std::string neededFor(const std::string& id) {
  if (id == "TOP") return "every step's depth (and so e_pos_z, e_splz's CMM side)";
  const auto u = id.find('_');
  if (u == std::string::npos) return "the evaluation";
  const std::string step = id.substr(1, u - 1), face = id.substr(u + 1);
  if (face == "F") return "step " + step + "'s depth and floor slopes";
  return "step " + step + "'s width " + (face[0] == 'X' ? "X" : "Y") + ", wall tilt and Oz";
}


}  // namespace

PlannedCmmPoints plannedCmmPointsCsv(const std::string& text, const std::string& file) {
  const CsvTable t = parseCsv(text, file);
  const char* need[] = {"feature", "x_mm", "y_mm", "z_mm"};
  for (const char* n : need)
    if (t.column(n) < 0)
      throw InputError(file, t.header_line, std::string("the CMM plan needs the column '") + n + "' (feature,point,x_mm,y_mm,z_mm,nx,ny,nz)");
  PlannedCmmPoints out;
  for (const auto& r : t.rows)
    out[r.fields[static_cast<std::size_t>(t.column("feature"))]].emplace_back(t.number(r, t.column("x_mm")), t.number(r, t.column("y_mm")),
                                                                               t.number(r, t.column("z_mm")));
  if (out.empty()) throw InputError(file, 0, "no planned CMM points");
  return out;
}

PlannedCmmPoints swPlannedCmmPoints(const parts::PlanManifest& m) {
  if (m.sw.cmm_plan.empty())
    throw InputError(m.file, 0, "stepped_workpiece.cmm_plan: not given; the stated planes are evaluated at the plan's CMM points");
  const std::string path = (std::filesystem::path(m.file).parent_path() / m.sw.cmm_plan).string();
  if (!std::filesystem::is_regular_file(path))
    throw InputError(m.file, 0, "stepped_workpiece.cmm_plan: " + path + " is not there; evaluating from stated features places the "
                                "plan's CMM points on each stated plane: keep the CMM plan beside plan.json");
  return plannedCmmPointsCsv(readFile(path), path);
}

SwStatedCmm swCmmFromFeatures(const parts::PlanManifest& m, const std::vector<FeatureActual>& rows, const PlannedCmmPoints& planned,
                              const std::string& file, const std::string& format) {
  const FeatureMatch match = matchFeatureActuals(rows, m);
  SwStatedCmm out;
  out.from.file = file;
  out.from.format = format;
  out.from.assigned_by = match.assigned_by;
  out.from.other_kinds = match.other_kinds;
  out.criterion_note = fittingCriterionNote(match);
  for (const auto& u : match.unmatched) out.from.unmatched.push_back(unmatchedText(u));
  for (const auto& f : m.features)
    if (f.nominal.kind == "plane" && !match.find(f.nominal.id))
      throw InputError(file, 0, "feature " + f.nominal.id + " (" + f.nominal.role + "): not in the file, by its id or its nominal geometry; " +
                                    neededFor(f.nominal.id) + " need" + (f.nominal.id == "TOP" ? "s" : "") + " it (" +
                                    std::to_string(rows.size()) + " rows read, " + std::to_string(match.unmatched.size()) +
                                    " fit no plane" + (match.unmatched.empty() ? "" : ": " + unmatchedText(match.unmatched.front())) + ")");
  const auto placed = pointsOnStatedFeatures(match, planned, file, format);
  std::vector<SwPlane> planes = swPlanes(m, placed.points);
  const auto spec = swCmmPointU(m);
  for (auto& p : planes) {
    const StatedScatter& sc = placed.scatter.at(p.id);
    const auto* mf = match.find(p.id);
    const int n = sc.nAveraging();
    // The candidates, per measured point (um): the CMM's specification at the plane's centroid
    // (as the point route's slopes use it), the form's sigma, and a stated u of the location
    // along the normal spread back over the n points it was fitted from.
    SwStatedPlane s;
    s.id = p.id;
    s.row = sc.row;
    s.matched_by = mf->by_id ? "id" : "nominal geometry";
    s.n_stated = sc.n_stated;
    s.n_planned = sc.n_planned;
    s.form_um = sc.form_um;
    s.sigma_um = spec(p.point_mm.norm());
    s.sigma_from = "MPE";
    if (std::isfinite(sc.sigma_from_form_mm) && sc.sigma_from_form_mm * 1e3 > s.sigma_um)
      s.sigma_um = sc.sigma_from_form_mm * 1e3, s.sigma_from = "form";
    const double from_u = sc.sigmaFromStatedU_mm() * 1e3;
    if (std::isfinite(from_u) && from_u > s.sigma_um) s.sigma_um = from_u, s.sigma_from = "stated u";
    p.points = n;
    p.rms_um = s.sigma_um;
    for (int i = 0; i < 3; ++i) p.u_slope[i] = s.sigma_um * sc.point_scale * 1e-3 * p.slope_lever[i];
    p.slope_u_from_spec = s.sigma_from != "form";
    p.form_dof = s.sigma_from == "form" ? sc.form_dof : 0.0;
    p.stated = true;
    out.from.planes.push_back(s);
  }
  out.scatter_notes = statedScatterNotes(placed.scatter);
  out.geometry = swGeometryFromPlanes(m, std::move(planes), file, "cmm");
  out.geometry.stated_basis =
      "from the stated features: per point sigma = the largest of MPE(L)/sqrt 3, form/(d2(n) sqrt((n-3)/n)) and a stated u x "
      "sqrt(n), over sqrt(n) of both planes (n: the file's count, else the plan's)";
  return out;
}

SwEvaluation evaluateSteppedWorkpieceFromFeatures(const parts::PlanManifest& m, const std::vector<FeatureActual>& rows,
                                                  const PlannedCmmPoints& planned, const std::string& file, const std::string& format,
                                                  const TtpPoints& probe) {
  auto cmm = swCmmFromFeatures(m, rows, planned, file, format);
  SwEvaluation e = evaluateSteppedWorkpiece(m, std::move(cmm.geometry), probe);
  int form = 0, mpe = 0, stated = 0;
  for (const auto& p : cmm.from.planes) (p.sigma_from == "form" ? form : p.sigma_from == "MPE" ? mpe : stated)++;
  e.notes.push_back("CMM side from the stated features of " + file + " (" + format + ", no points; matched by " + cmm.from.assigned_by +
                    "): the plan's CMM points placed on each stated plane, so the widths, depths, tilts, slopes and Oz are the "
                    "file's planes evaluated as the point route evaluates its own fits");
  e.notes.push_back(cmm.criterion_note);
  e.notes.push_back("lost against the point route: the real point layout and residuals (each plane's "
                    "per-point sigma is the largest of what is stated: form over d2(n) for " + std::to_string(form) +
                    " planes, the MPE for " + std::to_string(mpe) + ", a stated u for " + std::to_string(stated) +
                    "; the slopes' u from the planned layout), outliers (the file's planes are taken as they are), and the "
                    "line of each point (a refusal names the plane's row)");
  if (!cmm.from.unmatched.empty())
    e.notes.push_back(std::to_string(cmm.from.unmatched.size()) + " rows of the file fit no plane of the plan and are not used (listed "
                      "in cmm.from_features.unmatched)");
  for (auto& n : cmm.scatter_notes) e.notes.push_back(std::move(n));
  e.from_features = std::move(cmm.from);
  return e;
}

std::string swFromFeaturesReport(const SwFromFeatures& f) {
  std::ostringstream o;
  o << "\n## CMM planes from the stated features\n\n" << f.file << " (" << f.format << "; matched by " << f.assigned_by
    << "): per measured point the largest sigma of what is stated (um; n: the file's count, else the plan's).\n\n"
       "| plane | row | matched by | n stated | n planned | form um | sigma um | from |\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& p : f.planes)
    o << "| " << p.id << " | " << p.row << " | " << p.matched_by << " | " << (p.n_stated > 0 ? std::to_string(p.n_stated) : "-") << " | "
      << p.n_planned << " | " << (std::isfinite(p.form_um) ? formatNumber(p.form_um, 3) : "-") << " | " << formatNumber(p.sigma_um, 3)
      << " | " << p.sigma_from << " |\n";
  if (!f.unmatched.empty()) {
    o << "\nNot used:\n\n";
    for (const auto& u : f.unmatched) o << "- " << u << "\n";
  }
  return o.str();
}

std::string swFromFeaturesStdout(const SwFromFeatures& f) {
  std::string o = "CMM planes from the stated features of " + f.file + " (no points; " + std::to_string(f.planes.size()) +
                  " planes matched by " + f.assigned_by + ", " + std::to_string(f.unmatched.size()) +
                  (f.unmatched.size() == 1 ? " row fits" : " rows fit") + " no plane, " +
                  std::to_string(f.other_kinds) + " rows of other kinds not used)\n";
  for (const auto& u : f.unmatched) o += "  " + u + "\n";
  return o;
}

}  // namespace probeloop::evaluate
