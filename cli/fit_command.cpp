// `probeloop fit`: one geometric element fitted to a point cloud (evaluate/feature_fit.hpp).
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>

#include "cli/commands.hpp"
#include "cli/input_option.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "evaluate/feature_fit.hpp"
#include "evaluate/point_cloud.hpp"

namespace probeloop::cli {
namespace {

struct FitArgs {
  std::string kind, points, method = "ls", format = "auto", feature, cycle, material, approach;
  double tip_radius_mm = 0.0;
  std::optional<double> radius_mm, outliers_k, point_u_um;
  int outlier_rounds = 10;
  double outlier_max_fraction = 0.2;
  bool json = false, strict = false;
};

Eigen::Vector3d parseVector(const std::string& text, const std::string& option) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) {
    double x = 0;
    if (!parseFiniteNumber(part, x))
      throw InputError("", 0, option + " expects nx,ny,nz; '" + part + "' is not a number");
    v.push_back(x);
  }
  if (v.size() != 3 || Eigen::Vector3d(v[0], v[1], v[2]).norm() == 0.0)
    throw InputError("", 0, option + " expects three numbers nx,ny,nz, not all zero");
  return Eigen::Vector3d(v[0], v[1], v[2]).normalized();
}

int runFit(const FitArgs& a) {
  evaluate::FeatureFitRequest req;
  req.kind = *geometry::parseElementKind(a.kind);  // checked by CLI11
  req.options.method = *geometry::parseFitMethod(a.method);
  req.options.fixed_radius_mm = a.radius_mm;
  if (a.outliers_k)
    req.options.outliers = geometry::OutlierOptions{*a.outliers_k, a.outlier_rounds, a.outlier_max_fraction};
  req.tip_radius_mm = a.tip_radius_mm;
  if (!a.material.empty())
    req.side = a.material == "inside" ? geometry::MaterialSide::Inside : geometry::MaterialSide::Outside;
  if (!a.approach.empty()) req.approach = parseVector(a.approach, "--approach");
  if (a.point_u_um) req.point_u_mm = *a.point_u_um / 1000.0;
  const auto cloud = evaluate::readPointCloud(a.points, a.format, {a.feature, a.cycle, a.strict});
  auto rep = evaluate::fitFeature(cloud, req);
  // The exchange file's own warnings (lenient reading) first: they say where the points came from.
  rep.warnings.insert(rep.warnings.begin(), cloud.warnings.begin(), cloud.warnings.end());
  if (a.json) {
    std::fputs(evaluate::featureFitJson(cloud, rep).c_str(), stdout);
    for (const auto& w : rep.warnings) std::fprintf(stderr, "probeloop: warning: %s\n", w.c_str());
  } else {
    std::fputs(evaluate::featureFitText(cloud, rep).c_str(), stdout);
  }
  return 0;
}

}  // namespace

Subcommand addFitCommand(CLI::App& app) {
  auto fa = std::make_shared<FitArgs>();
  auto* fit = app.add_subcommand("fit", "Fit one geometric element to a point cloud (CSV, NIST .ds, XYZ, PLY) or to one "
                                "feature's points in a QIF 3.0 Results or DMIS output file");
  fit->add_option("kind", fa->kind, "line2d, line3d, plane, circle2d, circle3d, sphere, cylinder or cone")
      ->required()->check(CLI::IsMember({"line2d", "line3d", "plane", "circle2d", "circle3d", "sphere", "cylinder", "cone"}));
  fit->add_option("points", fa->points, "points file")->required()->check(inputFile("a points file (CSV, NIST .ds, XYZ, PLY, QIF or DMIS)"));
  fit->add_option("--method", fa->method, "ls (least squares), mz (minimum zone), mi (maximum inscribed), mc (minimum circumscribed)")
      ->check(CLI::IsMember({"ls", "mz", "mi", "mc"}))->capture_default_str();
  fit->add_option("--format", fa->format, "auto, csv, ds, xyz, ply, qif (QIF 3.0 Results) or dmis (DMIS output)")
      ->check(CLI::IsMember({"auto", "csv", "ds", "xyz", "ply", "qif", "dmis"}))->capture_default_str();
  fit->add_option("--feature", fa->feature, "points CSV: use the rows of this feature only; QIF/DMIS: this feature's measured "
                  "points (required when the file holds several)");
  fit->add_flag("--strict", fa->strict, "QIF or DMIS: refuse what the lenient reader would read with a warning (docs/interop.md)");
  fit->add_option("--cycle", fa->cycle, "points CSV: use the rows of this cycle only (required when the file holds several)");
  fit->add_option("--tip-radius", fa->tip_radius_mm, "stylus tip radius, mm: the points are tip centres")->capture_default_str();
  fit->add_option("--material", fa->material, "material side for tip compensation when the file has no approach directions: inside (ball, shaft) or outside (bore)")
      ->check(CLI::IsMember({"inside", "outside"}));
  fit->add_option("--approach", fa->approach, "one nominal approach direction nx,ny,nz for all points (planes, lines)");
  fit->add_option("--radius", fa->radius_mm, "known radius, mm (least squares: circle, sphere, cylinder)");
  fit->add_option("--outliers", fa->outliers_k, "eliminate outliers beyond k standard deviations (iterated)");
  fit->add_option("--outlier-rounds", fa->outlier_rounds, "at most this many elimination rounds")->capture_default_str();
  fit->add_option("--outlier-max-fraction", fa->outlier_max_fraction, "refuse to drop more than this fraction")->capture_default_str();
  fit->add_option("--point-u", fa->point_u_um, "point standard uncertainty, um (type B parameter uncertainties)");
  fit->add_flag("--json", fa->json, "print the JSON report instead of the text summary (warnings go to stderr)");
  return {fit, [fa] { return runFit(*fa); }};
}

}  // namespace probeloop::cli
