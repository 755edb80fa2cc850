#include "model/control_errors.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "model/stepped_evaluation_json.hpp"

namespace probeloop::model {

using nlohmann::json;

namespace {

// How a part's walls were joined, from its evaluation.json.
struct Joining {
  std::string transition;  // non_cutting | fast | continuous
  double feed_mm_per_min = 0;
};

Joining joiningOf(const json& e, const std::string& file) {
  if (!e.contains("transition") || !e.at("transition").is_string())
    throw InputError(file, 0, "transition: missing (an evaluation.json written before the control separation: run evaluate again)");
  Joining j{e.at("transition").get<std::string>(), 0};
  if (j.transition != "non_cutting" && j.transition != "fast" && j.transition != "continuous")
    throw InputError(file, 0, "transition: '" + j.transition + "'; expected non_cutting, fast or continuous");
  if (e.at("separation").empty()) throw InputError(file, 0, "separation: no steps");
  if (j.transition != "continuous") j.feed_mm_per_min = evaluationNumber(e, "transition_feed_mm_per_min", "", file);
  return j;
}

// The polynomial's leverage at x, g' (X'X)^-1 g with g = (1, x, x^2 …), x scaled by the largest
// measured value.
double leverage(const SteppedComponent& c, double x) {
  const int p = static_cast<int>(c.fit.function.p.size());
  const double s = c.x_max > 0 ? c.x_max : 1.0;
  Eigen::MatrixXd X(static_cast<Eigen::Index>(c.x.size()), p);
  for (std::size_t i = 0; i < c.x.size(); ++i)
    for (int j = 0; j < p; ++j) X(static_cast<Eigen::Index>(i), j) = std::pow(c.x[i] / s, j);
  Eigen::VectorXd g(p);
  for (int j = 0; j < p; ++j) g(j) = std::pow(x / s, j);
  return g.dot((X.transpose() * X).ldlt().solve(g));
}

// The reference's process error at a feed. Inside its feeds u is the line's out-of-sample u
// (u_pred: the points' u and the leave-one-out RMS); beyond them it grows with the line's
// leverage against the largest at a measured feed, sqrt(h(F) / h_max).
ThermalValue referenceAt(const SteppedComponent& c, double feed, const std::string& file) {
  if (!(feed >= 0) || feed > 2.0 * c.x_max)
    throw InputError(file, 0, "feed_mm_per_min: " + formatNumber(feed) + " mm/min lies beyond twice the reference's largest feed (" +
                                  formatNumber(c.x_max) + " mm/min): its process error is not extrapolated that far");
  ThermalValue v;
  v.value_um = c.at(feed);
  double h_max = 0;
  for (double x : c.x) h_max = std::max(h_max, leverage(c, x));
  const double h = leverage(c, feed);
  v.u_um = c.u_pred_um * (h > h_max && h_max > 0 ? std::sqrt(h / h_max) : 1.0);
  v.k95 = c.k95;
  v.basis = c.fit.function.formula();
  return v;
}

std::vector<ControlStep> separateAgainst(const ControlSeparation& c, const ThermalStages& st, const json& e,
                                         const std::string& file, const std::string& quantity) {
  const auto steps = separateProcess(st, e, file);  // one-part values and e_pt at each step's T and S
  std::vector<ControlStep> out;
  for (const auto& p : steps) {
    if (std::fabs(p.spindle_rpm - c.reference_spindle_rpm) > 0.5)
      throw InputError(file, 0, "separation[step " + std::to_string(p.step) + "].spindle_rpm: " + formatNumber(p.spindle_rpm) +
                                    " rpm; the reference's process error against the feed holds at its speed, " +
                                    formatNumber(c.reference_spindle_rpm) + " rpm");
    ControlStep s;
    s.experiment = p.experiment;
    s.quantity = quantity;
    s.step = p.step;
    s.feed_mm_per_min = p.feed_mm_per_min;
    s.spindle_rpm = p.spindle_rpm;
    s.temp_state_min = p.temp_state_min;
    s.one_part_x_um = p.one_part_x_um;
    s.u_one_part_x_um = p.u_one_part_x_um;
    s.one_part_y_um = p.one_part_y_um;
    s.u_one_part_y_um = p.u_one_part_y_um;
    s.pt_x = p.pt_x;
    s.pt_y = p.pt_y;
    s.ref_x = referenceAt(c.reference_x, s.feed_mm_per_min, file);
    s.ref_y = referenceAt(c.reference_y, s.feed_mm_per_min, file);
    const double tol = 1e-6 * c.reference_feed_max;
    s.extrapolated = s.feed_mm_per_min < c.reference_feed_min - tol || s.feed_mm_per_min > c.reference_feed_max + tol;
    // Eq. 3.11/3.12 (e_ctrl) and Eq. 3.15 reduced to W8 (e_cpr): the part's value minus e_pt
    // minus the reference's process error at the same feed.
    s.x_um = s.one_part_x_um - s.pt_x.value_um - s.ref_x.value_um;
    s.y_um = s.one_part_y_um - s.pt_y.value_um - s.ref_y.value_um;
    s.u_x_um = std::sqrt(s.u_one_part_x_um * s.u_one_part_x_um + s.pt_x.u_um * s.pt_x.u_um + s.ref_x.u_um * s.ref_x.u_um);
    s.u_y_um = std::sqrt(s.u_one_part_y_um * s.u_one_part_y_um + s.pt_y.u_um * s.pt_y.u_um + s.ref_y.u_um * s.ref_y.u_um);
    s.U_x_um = std::hypot(std::hypot(2 * s.u_one_part_x_um, s.pt_x.k95 * s.pt_x.u_um), s.ref_x.k95 * s.ref_x.u_um);
    s.U_y_um = std::hypot(std::hypot(2 * s.u_one_part_y_um, s.pt_y.k95 * s.pt_y.u_um), s.ref_y.k95 * s.ref_y.u_um);
    out.push_back(s);
  }
  return out;
}

}  // namespace

ControlSeparation separateControl(const ThermalStages& st, const json& reference, const std::string& reference_file,
                                  const json* transitions, const std::string& transitions_file, const json* force,
                                  const std::string& force_file) {
  requireSteppedEvaluation(reference, reference_file);
  const Joining ref = joiningOf(reference, reference_file);
  if (ref.transition == "continuous")
    throw InputError(reference_file, 0, "transition: continuous; the reference part (W8) joins its walls by non-cutting moves, the thesis's zero of control error (L1629)");
  ControlSeparation c;
  c.reference_experiment = reference.value("experiment", "");
  c.reference_transition_feed_mm_per_min = ref.feed_mm_per_min;
  const auto proc = separateProcess(st, reference, reference_file);
  std::vector<double> f, px, ux, py, uy;
  for (const auto& p : proc) {
    if (!f.empty() && std::fabs(p.spindle_rpm - c.reference_spindle_rpm) > 0.5)
      throw InputError(reference_file, 0, "separation[step " + std::to_string(p.step) + "].spindle_rpm: the reference part's speed changes (" +
                                              formatNumber(c.reference_spindle_rpm) + ", " + formatNumber(p.spindle_rpm) +
                                              " rpm); its process error against the feed needs one speed");
    c.reference_spindle_rpm = p.spindle_rpm;
    f.push_back(p.feed_mm_per_min);
    px.push_back(p.e_proc_x_um);
    ux.push_back(p.u_e_proc_x_um);
    py.push_back(p.e_proc_y_um);
    uy.push_back(p.u_e_proc_y_um);
  }
  c.reference_feed_min = *std::min_element(f.begin(), f.end());
  c.reference_feed_max = *std::max_element(f.begin(), f.end());
  const std::vector<Candidate> feed_forms{{Family::Polynomial, 1, false}, {Family::Polynomial, 2, false}};
  const auto forms = leavingTwoDof(feed_forms, f.size(), reference_file + ": the reference's process error against the feed");
  c.reference_x = fitSteppedComponent("e_proc_x_um", "feed_mm_per_min", f, px, ux, forms, reference_file);
  c.reference_y = fitSteppedComponent("e_proc_y_um", "feed_mm_per_min", f, py, uy, forms, reference_file);
  if (transitions) {
    requireSteppedEvaluation(*transitions, transitions_file);
    const Joining j = joiningOf(*transitions, transitions_file);
    if (j.transition == "continuous")
      throw InputError(transitions_file, 0, "transition: continuous; a part with a continuous path is the force part (--force, W5)");
    if (!(j.feed_mm_per_min > ref.feed_mm_per_min))
      throw InputError(transitions_file, 0, "transition_feed_mm_per_min: " + formatNumber(j.feed_mm_per_min) +
                                                " mm/min; the control error of Eq. 3.11 needs transitions faster than the reference's " +
                                                formatNumber(ref.feed_mm_per_min) + " mm/min");
    c.transitions_experiment = transitions->value("experiment", "");
    c.transition_feed_mm_per_min = j.feed_mm_per_min;
    c.transitions = separateAgainst(c, st, *transitions, transitions_file, "e_ctrl");
    for (auto& s : c.transitions) {
      s.x_um_per_mm_per_min = s.x_um / (j.feed_mm_per_min - ref.feed_mm_per_min);  // Eq. 3.13/3.14
      s.y_um_per_mm_per_min = s.y_um / (j.feed_mm_per_min - ref.feed_mm_per_min);
    }
  }
  if (force) {
    requireSteppedEvaluation(*force, force_file);
    const Joining j = joiningOf(*force, force_file);
    if (j.transition != "continuous")
      throw InputError(force_file, 0, "transition: " + j.transition + "; the force part (W5) is cut as one continuous path at the cutting feed");
    c.force_experiment = force->value("experiment", "");
    c.force = separateAgainst(c, st, *force, force_file, "e_cpr");
    std::vector<double> ff, ex, uex, ey, uey;
    for (const auto& s : c.force) {
      ff.push_back(s.feed_mm_per_min);
      ex.push_back(s.x_um);
      uex.push_back(s.u_x_um);
      ey.push_back(s.y_um);
      uey.push_back(s.u_y_um);
    }
    const auto fforms = leavingTwoDof(feed_forms, ff.size(), force_file + ": e_cpr against the feed");
    c.force_x = fitSteppedComponent("e_cpr_x_um", "feed_mm_per_min", ff, ex, uex, fforms, force_file);
    c.force_y = fitSteppedComponent("e_cpr_y_um", "feed_mm_per_min", ff, ey, uey, fforms, force_file);
    c.has_force_fit = true;
  }
  return c;
}

namespace {

json valueJson(const ThermalValue& v) {
  return {{"value", v.value_um}, {"u_c", v.u_um}, {"k", v.k95}, {"U", v.k95 * v.u_um}};
}

json fitJson(const SteppedComponent& c) {
  const auto& best = c.selection.candidates[static_cast<std::size_t>(c.selection.best)];
  json params = json::object();
  for (std::size_t i = 0; i < c.fit.function.p.size() && i < c.fit.names.size(); ++i) params[c.fit.names[i]] = c.fit.function.p[i];
  return {{"name", c.name}, {"variable", c.variable}, {"form", best.candidate.label()}, {"formula", c.fit.function.formula()},
          {"parameters", params}, {"loo_rms_um", best.loo_rms}, {"u_um", c.u_pred_um}, {"k95", c.k95}};
}

json stepJson(const ControlStep& s, bool slope) {
  json j{{"step", s.step}, {"feed_mm_per_min", s.feed_mm_per_min}, {"spindle_rpm", s.spindle_rpm},
         {"temp_state_min", s.temp_state_min},
         {"one_part_e_proc_x_um", {{"value", s.one_part_x_um}, {"u_c", s.u_one_part_x_um}}},
         {"one_part_e_proc_y_um", {{"value", s.one_part_y_um}, {"u_c", s.u_one_part_y_um}}},
         {"e_pt_x_um", valueJson(s.pt_x)}, {"e_pt_y_um", valueJson(s.pt_y)},
         {"reference_e_proc_x_um", valueJson(s.ref_x)}, {"reference_e_proc_y_um", valueJson(s.ref_y)},
         {"feed_extrapolated", s.extrapolated},
         {s.quantity + "_x_um", {{"value", s.x_um}, {"u_c", s.u_x_um}, {"U", s.U_x_um}}},
         {s.quantity + "_y_um", {{"value", s.y_um}, {"u_c", s.u_y_um}, {"U", s.U_y_um}}}};
  if (slope) {
    j[s.quantity + "_x_um_per_mm_per_min"] = s.x_um_per_mm_per_min;
    j[s.quantity + "_y_um_per_mm_per_min"] = s.y_um_per_mm_per_min;
  }
  return j;
}

}  // namespace

json controlJson(const ControlSeparation& c) {
  json j{{"reference", {{"experiment", c.reference_experiment},
                        {"transition_feed_mm_per_min", c.reference_transition_feed_mm_per_min},
                        {"spindle_rpm", c.reference_spindle_rpm},
                        {"feeds_mm_per_min", {c.reference_feed_min, c.reference_feed_max}},
                        {"e_proc_x_um", fitJson(c.reference_x)}, {"e_proc_y_um", fitJson(c.reference_y)}}}};
  if (!c.transitions.empty()) {
    json steps = json::array();
    for (const auto& s : c.transitions) steps.push_back(stepJson(s, true));
    j["transitions"] = {{"experiment", c.transitions_experiment}, {"transition_feed_mm_per_min", c.transition_feed_mm_per_min},
                        {"feed_scaling", "Eq. 3.13/3.14: e_ctrl(F) = slope x (F - F_ref), F_ref = the reference's transition feed"},
                        {"steps", steps}};
  }
  if (!c.force.empty()) {
    json steps = json::array();
    for (const auto& s : c.force) steps.push_back(stepJson(s, false));
    j["force"] = {{"experiment", c.force_experiment}, {"steps", steps}};
    if (c.has_force_fit) {
      j["force"]["e_cpr_x_um"] = fitJson(c.force_x);
      j["force"]["e_cpr_y_um"] = fitJson(c.force_y);
    }
  }
  return j;
}

std::string controlCsv(const ControlSeparation& c) {
  std::string s = "quantity,experiment,step,spindle_rpm,feed_mm_per_min,temp_state_min,one_part_e_proc_x_um,one_part_e_proc_y_um,"
                  "e_pt_x_um,e_pt_y_um,reference_e_proc_x_um,reference_e_proc_y_um,feed_extrapolated,value_x_um,U_x_um,value_y_um,U_y_um\n";
  auto f = [](double v) { return formatNumber(v, 4); };
  for (const auto* list : {&c.transitions, &c.force})
    for (const auto& p : *list)
      s += p.quantity + "," + p.experiment + "," + std::to_string(p.step) + "," + f(p.spindle_rpm) + "," + f(p.feed_mm_per_min) + "," +
           f(p.temp_state_min) + "," + f(p.one_part_x_um) + "," + f(p.one_part_y_um) + "," + f(p.pt_x.value_um) + "," +
           f(p.pt_y.value_um) + "," + f(p.ref_x.value_um) + "," + f(p.ref_y.value_um) + "," + (p.extrapolated ? "1" : "0") + "," +
           f(p.x_um) + "," + f(p.U_x_um) + "," + f(p.y_um) + "," + f(p.U_y_um) + "\n";
  return s;
}

std::string controlSummary(const ControlSeparation& c) {
  std::string s = "Control errors against " + c.reference_experiment + " (its transitions at " +
                  formatNumber(c.reference_transition_feed_mm_per_min) + " mm/min: the control errors are measured from them):\n"
                  "    its process error on the feed, X: " + steppedComponentSummary(c.reference_x) + "\n"
                  "    Y: " + steppedComponentSummary(c.reference_y) + "\n";
  auto line = [&](const ControlStep& p) {
    s += "  " + p.experiment + " step " + std::to_string(p.step) + " (F " + formatNumber(p.feed_mm_per_min) + (p.extrapolated ? ", extrapolated" : "") +
         "): " + p.quantity + "_x " + formatNumber(p.x_um, 2) + " +- " + formatNumber(p.U_x_um, 2) + ", " + p.quantity + "_y " +
         formatNumber(p.y_um, 2) + " +- " + formatNumber(p.U_y_um, 2) + " um\n";
  };
  if (!c.transitions.empty()) {
    s += " e_ctrl: " + c.transitions_experiment + "'s transitions at " + formatNumber(c.transition_feed_mm_per_min) + " mm/min (Eq. 3.11/3.12):\n";
    for (const auto& p : c.transitions) line(p);
  }
  if (!c.force.empty()) {
    s += " e_cpr: " + c.force_experiment + "'s continuous path (Eq. 3.15, reduced to the reference):\n";
    for (const auto& p : c.force) line(p);
    if (c.has_force_fit)
      s += "    e_cpr on the feed, X: " + steppedComponentSummary(c.force_x) + "\n    Y: " + steppedComponentSummary(c.force_y) + "\n";
  }
  return s;
}

}  // namespace probeloop::model
