#include "evaluate/piece_evaluation.hpp"

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "core/paths.hpp"
#include "evaluate/rotary_calibration.hpp"
#include "core/atomic_file.hpp"
#include "evaluate/qif_results.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/input_file.hpp"
#include "evaluate/feature_actuals.hpp"
#include "evaluate/input_warnings.hpp"
#include "interop/qif.hpp"
#include "evaluate/ingest.hpp"
#include "evaluate/sw_features.hpp"
#include "evaluate/ttp_ingest.hpp"

namespace probeloop::evaluate {

namespace {

// printf into a string (the sphere's texts were printed with these formats; byte-identical).
void appendf(std::string& out, const char* fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  va_list ap2;
  va_copy(ap2, ap);
  const int n = std::vsnprintf(nullptr, 0, fmt, ap);
  va_end(ap);
  if (n > 0) {
    std::string buf(static_cast<std::size_t>(n) + 1, '\0');
    std::vsnprintf(buf.data(), buf.size(), fmt, ap2);
    buf.resize(static_cast<std::size_t>(n));
    out += buf;
  }
  va_end(ap2);
}

EvaluationFiles sphere(const parts::PlanManifest& planned, const EvaluateRequest& r) {
  parts::PlanManifest m = planned;
  if (!r.cycle_starts.empty()) applyCycleStarts(m, r.cycle_starts);
  EvaluateOptions opt;
  opt.known_radius = !r.free_radius;
  EvaluationFiles f;
  std::vector<InputWarning> warnings;  // the QIF reader's (lenient reading)
  std::string text;
  // auto: a CSV with the feature-actuals columns is one (the points CSV has none of i,j,k,n_points).
  if (r.format == "features" || (r.format == "auto" && std::filesystem::is_regular_file(r.input_file))) text = readFile(r.input_file);
  if (r.format == "features" || (r.format == "auto" && looksLikeFeatureActuals(text))) {
    // Only the fitted centres, no points (issue 34): the same location errors from them.
    const auto rows = parseFeatureActuals(text, r.input_file, m.cycles);
    f.sphere = evaluateSphereCampaignFromFeatures(m, sphereCentresFromFeatures(rows, m), r.input_file, opt);
  } else if (r.format == "qif") {
    // The measured sphere features of a QIF 3.0 Results file, one MeasurementResults per cycle.
    // (A DMIS output holds one run: a campaign's cycles cannot be told apart in it; not read yet.)
    const auto doc = interop::parseQifResults(readFile(r.input_file), r.input_file, interop::CmmReadOptions{r.strict});
    warnings = inputWarnings(doc);
    // A sphere of points only is fitted as the point route fits it: known radius unless --free-radius.
    const std::optional<double> radius = r.free_radius ? std::nullopt : std::optional<double>(m.sphere_radius_mm);
    f.sphere = evaluateSphereCampaignFromFeatures(m, sphereCentresFromFeatures(featureActualsFromCmm(doc, m.cycles, radius), m),
                                                  r.input_file, opt);
  } else {
    if (r.format != "auto" && r.format != "linuxcnc" && r.format != "fanuc" && r.format != "csv")
      throw InputError("", 0, "--format '" + r.format + "': a sphere-artifact campaign takes auto, linuxcnc, fanuc, csv (points), "
                              "features or qif (sphere centres a CMM reports)");
    f.sphere = evaluateSphereCampaign(m, readProbeRecords(r.input_file, parsePointsFormat(r.format), m), opt);
  }
  const auto& e = *f.sphere;
  f.errors_csv = errorSeriesCsv(e);
  f.evaluation_json = withInputWarnings(evaluationJson(e, m), warnings);
  f.report_md = withInputWarningsSection(evaluationReport(e, m), warnings);
  f.stdout_text = sphereEvaluationStdout(e, r.out_dir);
  if (e.from_features)
    f.stdout_text = "Sphere centres from the feature file " + r.input_file + " (no points; " + std::to_string(e.other_features) +
                    " rows of other kinds not used)\n" + f.stdout_text;
  f.results_qif = evaluationQif(m, nullptr, f.errors_csv);
  if (m.tilt_axis) {
    // The tilting axis and C together on the machine's chain (issue 33), beside seed 004's
    // seven from the level positions.
    // Positions that cannot separate them still give seed 004's seven: say why, write those.
    try {
      const auto rc = calibrateRotaryAxes(m, e);
      f.rotary_json = rotaryCalibrationJson(rc);
      f.rotary_csv = rotaryErrorSeriesCsv(rc);
      f.stdout_text += rotaryCalibrationText(rc);
      f.stdout_text += "Wrote " + pathIn(r.out_dir, EvaluationFiles::kRotaryJson) + " (budgets) and " +
                       pathIn(r.out_dir, EvaluationFiles::kRotaryCsv) + " (drift since the reference cycle)\n";
    } catch (const GeometryError& g) {
      f.stdout_text += std::string("Rotary axes not calibrated: ") + g.what() + "\n";
    }
  }
  f.stdout_text += inputWarningLines(warnings);
  return f;
}

// The features a CMM states, when the file holds no points (issue 34): a feature CSV, or a QIF /
// DMIS file of features only; nullopt: the point route.
std::optional<StatedFeatureFile> statedFeatures(const std::string& fmt, const EvaluateRequest& r, const std::string& text) {
  if (fmt == "features") return StatedFeatureFile{"features", parseFeatureActuals(text, r.input_file), {}};
  if (fmt == "qif" || fmt == "dmis") return readStatedFeatures(r.input_file, text, r.strict);
  return std::nullopt;
}

EvaluationFiles thermalTestPiece(const parts::PlanManifest& m, const EvaluateRequest& r) {
  if (r.free_radius) throw InputError(r.input_file, 0, "--free-radius applies to sphere-artifact campaigns, not to the thermal test piece");
  const std::string text = readFile(r.input_file);
  const std::string fmt = r.format == "auto" ? detectTtpFormat(r.input_file, text) : r.format;
  TtpOptions opt;
  opt.gauge_resolution_um = r.gauge_resolution_um;
  TtpEvaluation e;
  std::optional<TtpPoints> points;
  std::vector<InputWarning> warnings;
  // Only the fitted features, no points (issue 34): the plan's points placed on them.
  const auto stated = statedFeatures(fmt, r, text);
  if (stated) {
    e = evaluateThermalTestPieceFromFeatures(m, stated->rows, r.input_file, stated->format, opt);
    warnings = stated->warnings;
  } else if (fmt == "cmm" || fmt == "qif" || fmt == "dmis") {  // a CSV export, QIF 3.0 Results or DMIS output
    points = readTtpCmmExport(r.input_file, text, m, r.strict);
    warnings = points->warnings;
    e = evaluateThermalTestPiece(m, *points, opt);
  } else if (fmt == "linuxcnc" || fmt == "fanuc" || fmt == "log" || fmt == "csv") {
    points = readTtpOnMachine(r.input_file, text, fmt, m);
    e = evaluateThermalTestPiece(m, *points, opt);
  } else if (fmt == "gauge") {
    if (!(r.gauge_resolution_um > 0)) throw InputError("", 0, "the gauge resolution must be positive");
    e = evaluateThermalTestPieceGauge(m, readTtpGauge(r.input_file, text, m), opt);
  } else {
    throw InputError("", 0, "--format '" + r.format + "': expected auto, cmm, qif, dmis, features, linuxcnc, fanuc, csv or gauge");
  }
  if (!r.compare_with.empty()) e.comparison = compareSpans(e, r.compare_with);
  EvaluationFiles f;
  f.errors_csv = ttpErrorsCsv(e);
  f.results_qif = evaluationQif(m, points ? &*points : nullptr, f.errors_csv);
  f.evaluation_json = withInputWarnings(ttpEvaluationJson(e), warnings);
  f.report_md = withInputWarningsSection(ttpReport(e), warnings);
  f.stdout_text = ttpStdout(e, pathIn(r.out_dir, EvaluationFiles::kErrorsCsv), pathIn(r.out_dir, EvaluationFiles::kEvaluationJson),
                            pathIn(r.out_dir, EvaluationFiles::kReportMd));
  f.stdout_text += inputWarningLines(warnings);
  f.thermal_test_piece = std::move(e);
  return f;
}

// Seed 000 separates the errors from the CMM and the on-machine measurement of one part:
// both files together (the CMM export as the points, the probe log with --probe-log).
EvaluationFiles steppedWorkpiece(const parts::PlanManifest& m, const EvaluateRequest& r) {
  if (r.free_radius) throw InputError("", 0, "--free-radius does not apply to the stepped workpiece");
  if (r.probe_log.empty())
    throw InputError(r.input_file, 0, "the stepped workpiece is evaluated from its CMM export and its on-machine probe "
                                      "log together: give the log with --probe-log (seed 000 L761: CMM - probe)");
  const std::string text = readFile(r.input_file);
  const std::string fmt = r.format == "auto" ? detectTtpFormat(r.input_file, text) : r.format;
  if (fmt != "cmm" && fmt != "qif" && fmt != "dmis" && fmt != "features")
    throw InputError(r.input_file, 0, "expected the CMM export (feature,point,x_mm,y_mm,z_mm,..., QIF 3.0 Results or DMIS output) or "
                                      "its feature actuals, found a " + fmt + " file");
  const std::string log = readFile(r.probe_log);
  const std::string log_fmt = detectTtpFormat(r.probe_log, log);
  if (log_fmt == "cmm" || log_fmt == "gauge" || log_fmt == "qif" || log_fmt == "dmis" || log_fmt == "features")
    throw InputError(r.probe_log, 0, "--probe-log: expected the on-machine probe log (PT lines) or points CSV, found a " + log_fmt + " file");
  EvaluationFiles f;
  // Only the fitted planes, no points: the stated planes (sw_features.hpp); with points, the
  // point route as before.
  if (const auto stated = statedFeatures(fmt, r, text)) {
    f.stepped_workpiece = evaluateSteppedWorkpieceFromFeatures(m, stated->rows, swPlannedCmmPoints(m), r.input_file, stated->format,
                                                               readTtpOnMachine(r.probe_log, log, log_fmt, m));
    if (!r.compare_with.empty()) compareWithBefore(*f.stepped_workpiece, m, r.compare_with);
    const auto& e = *f.stepped_workpiece;
    f.errors_csv = swErrorsCsv(e);
    f.evaluation_json = withInputWarnings(swEvaluationJson(e), stated->warnings);
    f.report_md = withInputWarningsSection(swReport(e), stated->warnings);
    f.compensation_json = swCompensationFile(e);
    f.results_qif = evaluationQif(m, nullptr, f.errors_csv);  // no measured points to write
    f.stdout_text = swFromFeaturesStdout(*e.from_features) + swStdout(e, r.out_dir) + inputWarningLines(stated->warnings);
    return f;
  }
  const auto cmm = readTtpCmmExport(r.input_file, text, m, r.strict);
  f.stepped_workpiece = evaluateSteppedWorkpiece(m, cmm, readTtpOnMachine(r.probe_log, log, log_fmt, m));
  if (!r.compare_with.empty()) compareWithBefore(*f.stepped_workpiece, m, r.compare_with);
  const auto& e = *f.stepped_workpiece;
  f.errors_csv = swErrorsCsv(e);
  f.evaluation_json = withInputWarnings(swEvaluationJson(e), cmm.warnings);
  f.report_md = withInputWarningsSection(swReport(e), cmm.warnings);
  f.compensation_json = swCompensationFile(e);
  f.results_qif = evaluationQif(m, &cmm, f.errors_csv);
  f.stdout_text = swStdout(e, r.out_dir) + inputWarningLines(cmm.warnings);
  return f;
}

}  // namespace

namespace {

EvaluationFiles evaluateByKind(const parts::PlanManifest& m, const EvaluateRequest& r) {
  const parts::PieceKind kind = m.pieceKind();
  if (kind == parts::PieceKind::SphereArtifact) {
    if (!r.compare_with.empty())
      throw InputError("", 0, "--compare applies to the thermal test piece (seed 004 Table 7.2), not to a sphere-artifact campaign");
    return sphere(m, r);
  }
  if (!r.cycle_starts.empty())
    throw InputError(r.cycle_starts, 0, "--cycle-starts applies to a sphere-artifact campaign's cycles, not to a " + m.kind);
  if (!r.probe_log.empty() && kind != parts::PieceKind::SteppedWorkpiece)
    throw InputError("", 0, "--probe-log applies to the stepped workpiece (its CMM export and probe log together)");
  switch (kind) {
    case parts::PieceKind::ThermalTestPiece: return thermalTestPiece(m, r);
    case parts::PieceKind::SteppedWorkpiece: return steppedWorkpiece(m, r);
    case parts::PieceKind::SphereArtifact: return sphere(m, r);  // (returned above)
  }
  throw std::logic_error("evaluateByKind: a PieceKind without an evaluation");
}

}  // namespace

EvaluationFiles evaluateTestPiece(const parts::PlanManifest& m, const EvaluateRequest& r) {
  auto f = evaluateByKind(m, r);
  if (!f.results_qif.empty()) f.stdout_text += "  the results as QIF 3.0: " + pathIn(r.out_dir, EvaluationFiles::kResultsQif) + "\n";
  return f;
}

std::string sphereEvaluationStdout(const CampaignEvaluation& e, const std::string& out_dir) {
  std::string o;
  appendf(o, "Location errors of the C axis relative to cycle %d (least squares; U for k = 2)\n", e.reference_cycle);
  appendf(o, "%6s %9s", "cycle", "time_s");
  for (const auto* n : geometry::LocationErrors::names()) appendf(o, " %17s", n);
  appendf(o, "\n");
  for (const auto& c : e.cycles) {
    appendf(o, "%6d %9.0f", c.cycle, c.time_s);
    for (const auto& b : c.budgets) appendf(o, " %8.3f +- %5.3f", b.value, b.U);
    appendf(o, "\n");
  }
  if (e.formulas_applicable) {
    double worst = 0;
    for (const auto& c : e.cycles)
      for (int j = 0; j < 7; ++j) worst = std::max(worst, std::fabs(c.formulas->values()[j] - c.least_squares.values()[j]));
    appendf(o, "Seed 004 Eqs. 5.4-5.10 on positions %d,%d,%d,%d agree with least squares to %.1e\n", e.formula_positions[0],
            e.formula_positions[1], e.formula_positions[2], e.formula_positions[3], worst);
  }
  for (const auto& [c, why] : e.incomplete) appendf(o, "Cycle %d not evaluated: %s\n", c, why.c_str());
  appendf(o, "Wrote %s, %s (budgets) and %s (report)\n", pathIn(out_dir, EvaluationFiles::kErrorsCsv).c_str(),
          pathIn(out_dir, EvaluationFiles::kEvaluationJson).c_str(), pathIn(out_dir, EvaluationFiles::kReportMd).c_str());
  return o;
}

std::string sphereResolutionText(const Resolution& r, double step_um) {
  std::string o;
  appendf(o, "Resolution of the location errors for a %s um coordinate step (seed 004 Table 5.4):\n", formatNumber(step_um).c_str());
  appendf(o, "  %-10s %16s %16s\n", "error", "Eqs. 5.4-5.10", "least squares");
  for (int j = 0; j < 7; ++j) {
    std::string n = geometry::LocationErrors::names()[j];
    const std::string unit = j < 4 ? "um" : "um/m";
    n = n.substr(0, n.find('_'));
    const std::string f = r.formulas ? formatNumber((*r.formulas)[j], 4) + " " + unit : "n/a";
    appendf(o, "  %-10s %16s %16s\n", n.c_str(), f.c_str(), (formatNumber(r.least_squares[j], 4) + " " + unit).c_str());
  }
  return o;
}

std::string spherePredictionText(const parts::PlanManifest& m) {
  std::string o;
  const auto b = predictLocationErrorBudgets(m);
  appendf(o,
          "Predicted expanded uncertainty (k = 2) of each error of a cycle, before measuring\n"
          "(d/2 = %s mm, %d points per sphere; drift and the d/2 term depend on measured values):\n",
          formatNumber(m.radius_from_axis_mm).c_str(), m.pointsPerSphere());
  for (const auto& x : b)
    appendf(o, "  %-6s U = %7s %-4s  largest: %s\n", x.quantity.c_str(), formatNumber(x.U, 3).c_str(), x.unit.c_str(),
            x.contributions.empty() ? "" : x.contributions.front().input.c_str());
  return o;
}

std::string planPrediction(const parts::PlanManifest& m, double step_mm) {
  if (m.pieceKind() == parts::PieceKind::SphereArtifact)
    return sphereResolutionText(locationErrorResolution(m, step_mm), step_mm * 1e3) + spherePredictionText(m) +
           (m.tilt_axis ? rotaryIdentifiabilityText(m) : "");
  if (m.pieceKind() != parts::PieceKind::ThermalTestPiece) return "";
  std::string o;
  const auto p = predictThermalTestPiece(m);
  if (!p.note.empty()) {
    appendf(o, "No predicted uncertainty: %s\n", p.note.c_str());
    return o;
  }
  appendf(o,
          "Predicted expanded uncertainty (k = 2) of the thermal-test-piece errors, before measuring: from the planned\n"
          "points and the specifications alone (type B point scatter; no measured values, so the type A scatter and the\n"
          "terms that scale with the measured value are 0); per route the largest over the cutting cycles:\n");
  appendf(o, "  %-11s %-8s %12s  %-6s %s\n", "route", "error", "U", "cycle", "largest contribution");
  for (int route = 0; route < 2; ++route) {
    const auto& v = route == 0 ? p.cmm : p.on_machine;
    for (const auto& x : v)
      appendf(o, "  %-11s %-8s %7s %-4s  %-6d %s\n", route == 0 ? "CMM" : "on-machine", x.quantity.c_str(), formatNumber(x.U, 3).c_str(),
              x.unit.c_str(), x.cycle, x.largest.c_str());
  }
  return o;
}

}  // namespace probeloop::evaluate
