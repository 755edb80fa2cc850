#include "sim/cmm_stage.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <random>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "interop/measured_geometry.hpp"
#include "sim/material_removal.hpp"
#include "sim/random_streams.hpp"

namespace probeloop::sim {

std::vector<CmmPoint> readCmmPoints(const std::string& path) {
  const CsvTable t = parseCsv(readFile(path), path);
  const char* need[] = {"feature", "point", "x_mm", "y_mm", "z_mm", "nx", "ny", "nz"};
  for (const char* n : need)
    if (t.column(n) < 0)
      throw InputError(path, t.header_line, std::string("CMM points need the column '") + n +
                                                "' (feature,point,x_mm,y_mm,z_mm,nx,ny,nz)");
  std::vector<CmmPoint> out;
  for (const auto& r : t.rows) {
    CmmPoint p;
    p.line = r.line;
    p.feature = r.fields[static_cast<std::size_t>(t.column("feature"))];
    const double point = t.number(r, t.column("point"));
    if (!(point >= 0 && point <= 1e6) || point != std::floor(point))
      throw InputError(path, r.line, "point must be a whole number 0..1000000");
    p.point = static_cast<int>(point);
    p.nominal_mm = Eigen::Vector3d(t.number(r, t.column("x_mm")), t.number(r, t.column("y_mm")), t.number(r, t.column("z_mm")));
    p.normal = Eigen::Vector3d(t.number(r, t.column("nx")), t.number(r, t.column("ny")), t.number(r, t.column("nz")));
    if (std::fabs(p.normal.norm() - 1.0) > 1e-6)
      throw InputError(path, r.line, "nx,ny,nz must be a unit vector (length " + formatNumber(p.normal.norm()) + ")");
    out.push_back(p);
  }
  if (out.empty()) throw InputError(path, 0, "no CMM points");
  return out;
}

std::vector<CmmPoint> cmmPointsOfQifPlan(const interop::CmmDocument& plan) {
  std::vector<CmmPoint> out;
  for (const auto& f : plan.features) {
    if (f.name.empty()) throw InputError(plan.file, f.line, "a feature nominal without a Name (the export names each point's feature)");
    // What the CMM answers in must hold it (checked before the machine runs for hours).
    const bool kind_ok = f.kind == interop::CmmFeatureKind::Plane || f.kind == interop::CmmFeatureKind::Sphere ||
                         f.kind == interop::CmmFeatureKind::Cylinder;
    if (!kind_ok)
      throw InputError(plan.file, f.line, "feature " + f.name + ": a " + (f.kind_name.empty() ? cmmFeatureKindName(f.kind) : f.kind_name) +
                                              "; the simulated CMM measures planes, spheres and cylinders");
    const bool label_ok = f.name.size() <= 13 && std::isalpha(static_cast<unsigned char>(f.name[0])) &&
                          std::all_of(f.name.begin(), f.name.end(), [](unsigned char c) { return std::isalnum(c) || c == '_'; });
    if (!label_ok)
      throw InputError(plan.file, f.line, "feature '" + f.name + "': its DMIS labels need [A-Za-z][A-Za-z0-9_]*, at most 13 characters "
                                                              "(+ _Pnn for its points within 16)");
    if (!f.nominal.given || (f.kind != interop::CmmFeatureKind::Plane && !std::isfinite(f.nominal.diameter_mm)))
      throw InputError(plan.file, f.line, "feature " + f.name + ": no nominal geometry (location, and the diameter of a sphere or cylinder)");
    int k = 0;
    for (const auto& q : f.points) {
      CmmPoint p;
      p.feature = f.name;
      p.point = ++k;
      p.line = f.line;
      p.nominal_mm = q.p_mm;
      p.normal = q.normal;
      if (!(p.normal.norm() > 0))
        throw InputError(plan.file, f.line, "feature " + f.name + " point " + std::to_string(k) + ": no Normal (the CMM approaches along it)");
      out.push_back(p);
    }
  }
  if (out.empty()) throw InputError(plan.file, 0, "no planned points (NominalPointSets) to measure");
  return out;
}

void checkCmmMoves(const Stock& stock, const interop::CmmDocument& plan) {
  if (plan.moves.empty()) return;
  // A probing move returns to where it started (the CMM backs off after the touch).
  Eigen::Vector3d a = plan.moves.front().to_mm;
  for (std::size_t i = 1; i < plan.moves.size(); ++i) {
    const auto& m = plan.moves[i];
    const Eigen::Vector3d from = a;
    if (!m.probing) a = m.to_mm;
    const Eigen::Vector3d d = m.to_mm - from;
    const double len = d.norm();
    if (len < 1e-9) continue;
    const auto hit = stock.firstMaterial(from, d / len, len);
    const double allowed = m.probing ? len - 0.5 : len;  // a probing move ends on the surface
    if (hit && *hit < allowed) {
      const Eigen::Vector3d at = from + *hit * d / len;
      throw InputError(plan.file, m.line, std::string(m.probing ? "PTMEAS" : "GOTO") + " to " + formatNumber(m.to_mm.x(), 3) + "," +
                                              formatNumber(m.to_mm.y(), 3) + "," + formatNumber(m.to_mm.z(), 3) +
                                              ": the move enters the part at " + formatNumber(at.x(), 3) + "," + formatNumber(at.y(), 3) +
                                              "," + formatNumber(at.z(), 3) + " (" + formatNumber(*hit, 3) + " mm along it)");
    }
  }
}

interop::CmmDocument cmmResultsDocument(const interop::CmmDocument& plan, const std::vector<Eigen::Vector3d>& measured_mm) {
  interop::CmmDocument r = plan;
  std::size_t i = 0;
  for (auto& f : r.features) {
    for (auto& p : f.points) p.p_mm = measured_mm.at(i++);
    interop::fitMeasuredGeometry(f);
  }
  return r;
}

std::string measureOnCmm(const Stock& stock, const parts::Workpiece& w, const std::vector<CmmPoint>& points,
                         const std::string& file, std::uint64_t seed, double alpha_per_K, double search,
                         std::vector<Eigen::Vector3d>* measured_mm) {
  std::mt19937_64 rng(seed ^ 0xC3A5C85C97CB3127ULL);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double half_K = w.cmm.temperature_half_width_K;
  double dT_K = 0;
  if (half_K > 0) {
    std::mt19937_64 room(streamSeed(seed, 7));
    dT_K = std::uniform_real_distribution<double>(-half_K, half_K)(room);
  }
  const double alpha = std::isnan(alpha_per_K) ? w.material.alpha_per_K : alpha_per_K;
  const double scale = 1.0 + alpha * dT_K;  // the part as it is in the room, uncorrected
  const std::string mpe = " um" + (w.cmm.mpe_length_mm > 0 ? " + L/" + formatNumber(w.cmm.mpe_length_mm) : std::string());
  std::ostringstream o;
  if (half_K > 0)
    o << "# probeloop simulate: CMM export, part frame; the part at 20 C + dT, dT = " << formatNumber(dT_K, 6)
      << " K (drawn within +-" << formatNumber(half_K) << " K; the expansion alpha dT about the datum is not corrected, "
      << "seed 004 Eq. 7.6); MPE = " << formatNumber(w.cmm.mpe_constant_um) << mpe << "\n";
  else
    o << "# probeloop simulate: CMM export, workpiece frame at 20 C; MPE = " << formatNumber(w.cmm.mpe_constant_um) << mpe
      << "\n";
  o << "feature,point,x_mm,y_mm,z_mm,nx,ny,nz\n";
  for (const auto& p : points) {
    const Eigen::Vector3d from = p.nominal_mm + search * p.normal;
    const auto s = stock.firstMaterial(from, -p.normal, 2 * search);
    if (s && *s <= 0)
      throw InputError(file, p.line, "CMM point " + p.feature + " " + std::to_string(p.point) + ": the approach starts in material " +
                                         formatNumber(search) + " mm outside the nominal point (a narrow slot, or a wrong normal)");
    if (!s)
      throw InputError(file, p.line, "CMM point " + p.feature + " " + std::to_string(p.point) +
                                         ": no surface within " + formatNumber(search) + " mm of the nominal point along the normal");
    const double L = (p.nominal_mm - w.datum()).norm();
    const double mpe_um = w.cmm.mpe_constant_um + (w.cmm.mpe_length_mm > 0 ? L / w.cmm.mpe_length_mm : 0.0);
    Eigen::Vector3d surface = from - *s * p.normal;
    if (half_K > 0) surface = w.datum() + scale * (surface - w.datum());
    const Eigen::Vector3d m = surface + (mpe_um / 2) * 1e-3 * normal(rng) * p.normal;
    // The export's 0.1 um: QIF and CSV carry the same numbers.
    if (measured_mm)
      measured_mm->emplace_back(std::stod(formatNumber(m.x(), 4)), std::stod(formatNumber(m.y(), 4)), std::stod(formatNumber(m.z(), 4)));
    o << p.feature << "," << p.point << "," << formatNumber(m.x(), 4) << "," << formatNumber(m.y(), 4) << ","
      << formatNumber(m.z(), 4) << "," << formatNumber(p.normal.x(), 6) << "," << formatNumber(p.normal.y(), 6) << ","
      << formatNumber(p.normal.z(), 6) << "\n";
  }
  return o.str();
}

}  // namespace probeloop::sim
