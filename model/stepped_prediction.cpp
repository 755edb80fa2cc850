#include "model/stepped_prediction.hpp"

#include <cmath>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "model/stepped_evaluation_json.hpp"
#include "uncertainty/gum.hpp"

namespace probeloop::model {

using nlohmann::json;

SteppedComponent fitSteppedComponent(std::string name, std::string variable, std::vector<double> x, std::vector<double> y,
                                     std::vector<double> u, const std::vector<Candidate>& candidates, const std::string& file) {
  SteppedComponent c;
  c.name = std::move(name);
  c.variable = std::move(variable);
  c.x = std::move(x);
  c.y = std::move(y);
  c.u = std::move(u);
  c.selection = selectByBackwardPrediction(c.x, c.y, candidates);
  if (c.selection.best < 0)
    throw GeometryError(file + ": " + c.name + " against " + c.variable + ": " + c.selection.sentence);
  const auto& best = c.selection.candidates[static_cast<std::size_t>(c.selection.best)];
  c.fit = best.fit;
  double su = 0;
  int n = 0;
  for (double v : c.u)
    if (v > 0) su += v * v, ++n;
  const double rms_u = n ? std::sqrt(su / n) : 0.0;
  c.u_pred_um = std::hypot(rms_u, best.loo_rms);
  // Welch-Satterthwaite (JCGM 100 G.4.1): the points' own u are type B budgets (many dof), the
  // leave-one-out RMS is type A with n - parameters dof; k from Student's t at the effective dof.
  const double dof = std::max(1, best.fit.n - best.fit.parameters);
  const double ratio = best.loo_rms > 0 ? c.u_pred_um / best.loo_rms : 1e6;
  c.k95 = uncertainty::coverageFactor(0.95, std::min(1e6, dof * std::pow(ratio, 4)));
  for (double v : c.x) c.x_max = std::max(c.x_max, v);
  return c;
}

double evaluationNumber(const json& o, const char* key, const std::string& where, const std::string& file) {
  if (!o.is_object() || !o.contains(key) || !o.at(key).is_number())
    throw InputError(file, 0, where + key + ": missing (expected the evaluation.json of a stepped workpiece)");
  const double v = o.at(key).get<double>();
  if (!std::isfinite(v)) throw InputError(file, 0, where + key + ": not finite");
  return v;
}

std::pair<double, double> evaluationBudget(const json& o, const char* key, const std::string& where, const std::string& file) {
  if (!o.contains(key)) throw InputError(file, 0, where + key + ": missing (expected the evaluation.json of a stepped workpiece)");
  return {evaluationNumber(o.at(key), "value", where + key + ".", file),
          evaluationNumber(o.at(key), "u_c", where + key + ".", file)};
}

void requireSteppedEvaluation(const json& e, const std::string& file) {
  if (!e.is_object() || e.value("kind", "") != "stepped_workpiece" || !e.contains("separation") || !e.at("separation").is_array())
    throw InputError(file, 0, "kind: expected the evaluation.json of a stepped workpiece (probeloop evaluate … --probe-log)");
}

double SteppedComponent::at(double v) const {
  if (!(v >= 0) || v > 2.0 * x_max)
    throw GeometryError(name + ": " + variable + " " + formatNumber(v, 3) + " lies beyond twice the largest measured (" +
                        formatNumber(x_max, 3) + "): the separated part cannot predict it");
  return fit.function.evaluate(v);
}

SteppedPredictor steppedPredictorBase(const json& e, const std::string& file) {
  requireSteppedEvaluation(e, file);
  SteppedPredictor p;
  p.file = file;
  p.experiment = e.value("experiment", "");
  const auto& seps = e.at("separation");
  if (seps.size() < 3) throw InputError(file, 0, "separation: " + std::to_string(seps.size()) + " steps; a prediction needs at least 3");
  const char* kname[3] = {"k_pos_x_um_per_mm", "k_pos_y_um_per_mm", "k_pos_z_um_per_mm"};
  for (int a = 0; a < 3; ++a) {
    const auto [v, u] = evaluationBudget(e, kname[a], "", file);
    p.k_um_per_mm[a] = v;
    p.u_k_um_per_mm[a] = u;
  }
  // The tool's diameter: the tool centre's travel minus the size (cmm.steps[].size_mm).
  const auto& cs = e.contains("cmm") ? e.at("cmm").value("steps", json::array()) : json::array();
  if (cs.empty()) throw InputError(file, 0, "cmm.steps: missing (the sizes of the steps)");
  p.tool_d_mm = evaluationNumber(seps[0], "travel_tool_mm", "separation[0].", file) - evaluationNumber(cs[0], "size_mm", "cmm.steps[0].", file);
  p.probe_d_mm = evaluationNumber(seps[0], "travel_probe_mm", "separation[0].", file) - evaluationNumber(cs[0], "size_mm", "cmm.steps[0].", file);
  return p;
}

SteppedPredictor steppedPredictorFromEvaluation(const json& e, const std::string& file) {
  SteppedPredictor p = steppedPredictorBase(e, file);
  const auto& seps = e.at("separation");
  std::vector<double> F, T{0.0}, px, py, ux, uy, splz{0.0}, us{0.0};
  double speed = -1;
  for (std::size_t i = 0; i < seps.size(); ++i) {
    const auto& s = seps[i];
    const std::string where = "separation[" + std::to_string(i) + "].";
    const double S = evaluationNumber(s, "spindle_rpm", where, file);
    if (speed >= 0 && std::fabs(S - speed) > 0.5)
      throw InputError(file, 0, where + "spindle_rpm: " + formatNumber(S) + ", the other steps " + formatNumber(speed) +
                                    ": one part gives one thermal stage (its speed must not change)");
    speed = S;
    F.push_back(evaluationNumber(s, "feed_mm_per_min", where, file));
    T.push_back(evaluationNumber(s, "temp_state_min", where, file));
    const auto bx = evaluationBudget(s, "e_proc_x_um", where, file), by = evaluationBudget(s, "e_proc_y_um", where, file), bz = evaluationBudget(s, "e_splz_um", where, file);
    px.push_back(bx.first);
    ux.push_back(bx.second);
    py.push_back(by.first);
    uy.push_back(by.second);
    splz.push_back(bz.first);
    us.push_back(bz.second);
  }
  p.speed_ref_rpm = speed;
  const std::vector<Candidate> feed_forms{{Family::Polynomial, 1, true}, {Family::Polynomial, 2, true}, {Family::Hyperbolic, 0, false}};
  const std::vector<Candidate> time_forms{{Family::SaturatingExponential, 0, false},
                                          {Family::Polynomial, 1, true},
                                          {Family::Polynomial, 2, true},
                                          {Family::Hyperbolic, 0, false}};
  p.proc_x = fitSteppedComponent("e_proc_x_um", "feed_mm_per_min", F, px, ux, feed_forms, file);
  p.proc_y = fitSteppedComponent("e_proc_y_um", "feed_mm_per_min", F, py, uy, feed_forms, file);
  p.splz = fitSteppedComponent("e_splz_um", "temp_state_min", T, splz, us, time_forms, file);
  return p;
}

std::vector<SteppedPrediction> predictSteppedErrors(const SteppedPredictor& p, const std::vector<SteppedConditions>& steps) {
  std::vector<SteppedPrediction> out;
  for (const auto& c : steps) {
    if (!(c.spindle_rpm >= 0)) throw GeometryError("step " + std::to_string(c.step) + ": negative spindle speed");
    SteppedPrediction r;
    r.step = c.step;
    const double L = c.size_mm + p.tool_d_mm, scale = p.speed_ref_rpm > 0 ? c.spindle_rpm / p.speed_ref_rpm : 1.0;
    if (p.proc_per_rev && !(c.spindle_rpm > 0))
      throw GeometryError("step " + std::to_string(c.step) + ": the process error per revolution needs a spindle speed > 0");
    const double fx = p.proc_per_rev ? 1000.0 * c.feed_mm_per_min / c.spindle_rpm : c.feed_mm_per_min;
    r.width_x_um = p.k_um_per_mm[0] * L + p.proc_x.at(fx);
    r.width_y_um = p.k_um_per_mm[1] * L + p.proc_y.at(fx);
    const double Lp = c.size_mm + p.probe_d_mm;
    r.U_width_x_um = std::hypot(2 * p.u_k_um_per_mm[0] * Lp, p.proc_x.k95 * p.proc_x.u_pred_um);
    r.U_width_y_um = std::hypot(2 * p.u_k_um_per_mm[1] * Lp, p.proc_y.k95 * p.proc_y.u_pred_um);
    if (p.thermal) {
      const ThermalTerms t = p.thermal(c.temp_state_min, c.spindle_rpm);
      r.width_x_um += t.pt_x_um;
      r.width_y_um += t.pt_y_um;
      r.depth_um = p.k_um_per_mm[2] * c.depth_mm - t.splz_um;
      r.U_width_x_um = std::hypot(r.U_width_x_um, t.U_pt_x_um);
      r.U_width_y_um = std::hypot(r.U_width_y_um, t.U_pt_y_um);
      r.U_depth_um = std::hypot(2 * p.u_k_um_per_mm[2] * c.depth_mm, t.U_splz_um);
    } else {
      r.depth_um = p.k_um_per_mm[2] * c.depth_mm - scale * p.splz.at(c.temp_state_min);
      r.U_depth_um = std::hypot(2 * p.u_k_um_per_mm[2] * c.depth_mm, scale * p.splz.k95 * p.splz.u_pred_um);
    }
    out.push_back(r);
  }
  return out;
}

std::string steppedComponentSummary(const SteppedComponent& c) {
  const auto& best = c.selection.candidates[static_cast<std::size_t>(c.selection.best)];
  std::string params;
  for (std::size_t i = 0; i < c.fit.function.p.size(); ++i)
    params += (i ? ", " : "") + (i < c.fit.names.size() ? c.fit.names[i] : "p" + std::to_string(i)) + " " + formatSignificant4(c.fit.function.p[i]);
  return c.name + "(" + c.variable + "): " + best.candidate.label() + " [" + params + "], the best of " +
         std::to_string(c.selection.candidates.size()) + " forms by leave-one-out (RMS " + formatNumber(best.loo_rms, 3) + " um over " +
         std::to_string(c.x.size()) + " points); u " + formatNumber(c.u_pred_um, 3) + " um";
}

std::string steppedPredictorSummary(const SteppedPredictor& p) {
  const std::string cond = p.thermal ? " (" + p.experiment + ", with the campaign's stages)"
                                     : " (" + p.experiment + ", " + formatNumber(p.speed_ref_rpm) + " rpm)";
  std::string s = "Predicted from " + p.file + cond + ": e_pos = k L with k_x " +
                  formatNumber(p.k_um_per_mm[0], 4) + ", k_y " + formatNumber(p.k_um_per_mm[1], 4) + ", k_z " +
                  formatNumber(p.k_um_per_mm[2], 4) + " um/mm\n";
  for (const auto* c : {&p.proc_x, &p.proc_y, &p.splz}) {
    if (c == &p.splz && p.thermal) continue;  // the campaign's stages give e_splz
    s += "  " + steppedComponentSummary(*c) + "\n";
  }
  if (p.thermal) s += "  e_pt_x, e_pt_y, e_splz(T, S): " + p.thermal_summary + "\n";
  return s;
}

}  // namespace probeloop::model
