#include "model/thermal_stages.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "model/stepped_evaluation_json.hpp"

namespace probeloop::model {

using nlohmann::json;

namespace {

struct StagePoint {
  std::string experiment, file;
  int step = 0;
  double feed = 0, T = 0, px = 0, ux = 0, py = 0, uy = 0, splz = 0, us = 0;
};

// Forms with a free intercept (L844) for e_pt; through (0, 0) for e_splz (stepped_prediction).
const std::vector<Candidate>& ptForms() {
  static const std::vector<Candidate> f{{Family::Polynomial, 1, false}, {Family::Polynomial, 2, false},
                                        {Family::SaturatingExponential, 0, false}};
  return f;
}
const std::vector<Candidate>& splzForms() {
  static const std::vector<Candidate> f{{Family::SaturatingExponential, 0, false}, {Family::Polynomial, 1, true},
                                        {Family::Polynomial, 2, true}, {Family::Hyperbolic, 0, false}};
  return f;
}

double componentAt(const ThermalStage& s, ThermalComponent c, double T, double* u, double* k) {
  const SteppedComponent& sc = c == ThermalComponent::PtX ? s.one_part_x : c == ThermalComponent::PtY ? s.one_part_y : s.splz;
  *u = sc.u_pred_um;
  *k = sc.k95;
  return c == ThermalComponent::Splz ? sc.at(T) : sc.at(T) - sc.at(0);
}

std::string rpm(double S) { return formatNumber(S) + " rpm"; }

}  // namespace

std::vector<Candidate> leavingTwoDof(const std::vector<Candidate>& forms, std::size_t n, const std::string& what) {
  std::vector<Candidate> out;
  std::size_t fewest = 99;
  for (const auto& c : forms) {
    const std::size_t p = parameterNames(c.family, c.degree).size() - (c.through_origin ? 1 : 0);
    fewest = std::min(fewest, p);
    if (p + 2 <= n) out.push_back(c);
  }
  if (out.empty())
    throw GeometryError(what + ": " + std::to_string(n) + " points; the simplest form has " + std::to_string(fewest) +
                        " parameters and must leave 2 degrees of freedom: at least " + std::to_string(fewest + 2) + " points");
  return out;
}

ThermalValue ThermalStages::at(ThermalComponent c, double T, double S) const {
  if (stages.empty()) throw GeometryError("thermal stages: none (give the evaluations of parts cut at one feed and one speed)");
  if (!(S >= 0) || !std::isfinite(S)) throw GeometryError("thermal stages: spindle speed " + formatNumber(S) + " rpm is not a speed");
  ThermalValue v;
  double u = 0, k = 2;
  const ThermalStage &lo = stages.front(), &hi = stages.back();
  const ThermalStage* own = nullptr;  // a stage at this speed (L1445: "their respective equations")
  for (const auto& s : stages)
    if (std::fabs(s.spindle_rpm - S) <= 0.5) own = &s;
  if (own || S <= lo.spindle_rpm || S >= hi.spindle_rpm) {
    // One stage at its own speed; beyond the measured speeds, scaled by S / S_stage (Eq. 3.9/3.10).
    const ThermalStage& s = own ? *own : S <= lo.spindle_rpm ? lo : hi;
    const double w = own || s.spindle_rpm <= 0 ? 1.0 : S / s.spindle_rpm;
    v.value_um = w * componentAt(s, c, T, &u, &k);
    v.u_um = std::fabs(w) * u;
    v.k95 = k;
    v.basis = std::fabs(w - 1) < 1e-12 ? "stage " + rpm(s.spindle_rpm)
                                       : formatNumber(S) + "/" + formatNumber(s.spindle_rpm) + " x stage " + rpm(s.spindle_rpm);
    return v;
  }
  std::size_t b = 1;
  while (stages[b].spindle_rpm < S) ++b;
  const ThermalStage &sa = stages[b - 1], &sb = stages[b];
  // Linear in S: the weight of stage b grows from 0 at S_a to 1 at S_b (the thesis's Eq. 3.7/3.8
  // put it on the other stage, notes §4.5).
  const double wb = (S - sa.spindle_rpm) / (sb.spindle_rpm - sa.spindle_rpm), wa = 1 - wb;
  double ua = 0, ka = 2, ub = 0, kb = 2;
  const double fa = componentAt(sa, c, T, &ua, &ka), fb = componentAt(sb, c, T, &ub, &kb);
  v.value_um = wa * fa + wb * fb;
  v.u_um = std::hypot(wa * ua, wb * ub);
  v.k95 = std::max(ka, kb);
  v.basis = formatNumber(wa, 4) + " x stage " + rpm(sa.spindle_rpm) + " + " + formatNumber(wb, 4) + " x stage " + rpm(sb.spindle_rpm);
  return v;
}

ThermalStages thermalStagesFromEvaluations(const std::vector<std::pair<json, std::string>>& parts) {
  std::map<long, std::vector<StagePoint>> by_speed;  // rounded rpm -> points
  std::map<long, double> feed_of;
  json sources = json::array();
  for (const auto& [e, file] : parts) {
    requireSteppedEvaluation(e, file);
    const auto& seps = e.at("separation");
    double S0 = -1, F0 = -1;
    std::vector<StagePoint> pts;
    for (std::size_t i = 0; i < seps.size(); ++i) {
      const auto& s = seps[i];
      const std::string where = "separation[" + std::to_string(i) + "].";
      StagePoint p;
      p.experiment = e.value("experiment", "");
      p.file = file;
      p.step = s.value("step", static_cast<int>(i) + 1);
      const double S = evaluationNumber(s, "spindle_rpm", where, file);
      p.feed = evaluationNumber(s, "feed_mm_per_min", where, file);
      if (i > 0 && std::fabs(S - S0) > 0.5)
        throw InputError(file, 0, where + "spindle_rpm: " + formatNumber(S) + ", step 1 " + formatNumber(S0) +
                                      ": a thermal stage is cut at one speed (W1, W4, W6, W7)");
      if (i > 0 && std::fabs(p.feed - F0) > 1e-6)
        throw InputError(file, 0, where + "feed_mm_per_min: " + formatNumber(p.feed) + ", step 1 " + formatNumber(F0) +
                                      ": a thermal stage keeps its feed (its process error must not change; a part cut "
                                      "at changing feeds, W8, is the process part: --process)");
      S0 = S;
      F0 = p.feed;
      p.T = evaluationNumber(s, "temp_state_min", where, file);
      std::tie(p.px, p.ux) = evaluationBudget(s, "e_proc_x_um", where, file);
      std::tie(p.py, p.uy) = evaluationBudget(s, "e_proc_y_um", where, file);
      std::tie(p.splz, p.us) = evaluationBudget(s, "e_splz_um", where, file);
      pts.push_back(p);
    }
    if (pts.empty()) throw InputError(file, 0, "separation: no steps");
    sources.push_back({{"file", file},
                       {"evaluation", {{"kind", "stepped_workpiece"}, {"experiment", e.value("experiment", "")}, {"separation", seps}}}});
    const long key = std::lround(S0);
    if (feed_of.count(key) && std::fabs(feed_of[key] - F0) > 1e-6)
      throw InputError(file, 0, "separation[0].feed_mm_per_min: " + formatNumber(F0) + ", another part at " + rpm(S0) + " was cut at " +
                                    formatNumber(feed_of[key]) + ": parts pooled into one stage need the same feed");
    feed_of[key] = F0;
    auto& v = by_speed[key];
    v.insert(v.end(), pts.begin(), pts.end());
  }
  ThermalStages st;
  st.sources = sources;
  for (const auto& [key, pts] : by_speed) {
    ThermalStage s;
    s.spindle_rpm = static_cast<double>(key);
    s.feed_mm_per_min = feed_of[key];
    const std::string label = "stage " + rpm(s.spindle_rpm);
    if (!(s.spindle_rpm > 0)) throw GeometryError(label + ": a thermal stage is cut with the spindle turning");
    if (pts.size() < 4)
      throw GeometryError(label + ": " + std::to_string(pts.size()) + " steps; a thermal curve with a free intercept needs at least 4 "
                                  "(a line leaves 2 degrees of freedom)");
    std::vector<double> T, px, ux, py, uy, sT{0.0}, sz{0.0}, su{0.0};
    for (const auto& p : pts) {
      if (std::find(s.files.begin(), s.files.end(), p.file) == s.files.end()) {
        s.files.push_back(p.file);
        s.experiments.push_back(p.experiment);
      }
      s.steps.push_back(p.step);
      s.point_experiments.push_back(p.experiment);
      T.push_back(p.T);
      px.push_back(p.px);
      ux.push_back(p.ux);
      py.push_back(p.py);
      uy.push_back(p.uy);
      sT.push_back(p.T);
      sz.push_back(p.splz);
      su.push_back(p.us);
    }
    s.one_part_x = fitSteppedComponent("e_pt_x_um", "temp_state_min", T, px, ux, leavingTwoDof(ptForms(), T.size(), label + " e_pt_x"), label);
    s.one_part_y = fitSteppedComponent("e_pt_y_um", "temp_state_min", T, py, uy, leavingTwoDof(ptForms(), T.size(), label + " e_pt_y"), label);
    s.splz = fitSteppedComponent("e_splz_um", "temp_state_min", sT, sz, su, leavingTwoDof(splzForms(), sT.size(), label + " e_splz"), label);
    st.stages.push_back(std::move(s));
  }
  if (st.stages.empty()) throw GeometryError("thermal stages: no part given");
  return st;
}

std::vector<ProcessStep> separateProcess(const ThermalStages& st, const json& e, const std::string& file) {
  requireSteppedEvaluation(e, file);
  std::vector<ProcessStep> out;
  const auto& seps = e.at("separation");
  for (std::size_t i = 0; i < seps.size(); ++i) {
    const auto& s = seps[i];
    const std::string where = "separation[" + std::to_string(i) + "].";
    ProcessStep p;
    p.experiment = e.value("experiment", "");
    p.step = s.value("step", static_cast<int>(i) + 1);
    p.feed_mm_per_min = evaluationNumber(s, "feed_mm_per_min", where, file);
    p.spindle_rpm = evaluationNumber(s, "spindle_rpm", where, file);
    p.temp_state_min = evaluationNumber(s, "temp_state_min", where, file);
    std::tie(p.one_part_x_um, p.u_one_part_x_um) = evaluationBudget(s, "e_proc_x_um", where, file);
    std::tie(p.one_part_y_um, p.u_one_part_y_um) = evaluationBudget(s, "e_proc_y_um", where, file);
    p.pt_x = st.at(ThermalComponent::PtX, p.temp_state_min, p.spindle_rpm);
    p.pt_y = st.at(ThermalComponent::PtY, p.temp_state_min, p.spindle_rpm);
    p.e_proc_x_um = p.one_part_x_um - p.pt_x.value_um;
    p.e_proc_y_um = p.one_part_y_um - p.pt_y.value_um;
    p.u_e_proc_x_um = std::hypot(p.u_one_part_x_um, p.pt_x.u_um);
    p.u_e_proc_y_um = std::hypot(p.u_one_part_y_um, p.pt_y.u_um);
    p.U_e_proc_x_um = std::hypot(2 * p.u_one_part_x_um, p.pt_x.k95 * p.pt_x.u_um);
    p.U_e_proc_y_um = std::hypot(2 * p.u_one_part_y_um, p.pt_y.k95 * p.pt_y.u_um);
    out.push_back(p);
  }
  return out;
}

SteppedPredictor steppedPredictorFromCampaign(const ThermalStages& st, const json& process, const std::string& file) {
  // The process part may change its speed from step to step (the chip load is its variable): only
  // k and the diameters are read from it, its e_splz is the stages'.
  SteppedPredictor p = steppedPredictorBase(process, file);
  // e_proc(F) refitted to the process part's steps with the thermal error taken out.
  // The process error against the feed per revolution (the chip load, 1000 F / S): the process
  // part's steps with e_pt taken out, and each stage's intercept, its process error at its own
  // speed (the stages cut at 1000 and 5500 rpm load the tool differently at the same feed).
  const auto steps = separateProcess(st, process, file);
  std::vector<double> f, px, ux, py, uy;
  for (const auto& s : steps) {
    if (!(s.spindle_rpm > 0)) throw InputError(file, 0, "separation[].spindle_rpm: must be positive");
    f.push_back(1000.0 * s.feed_mm_per_min / s.spindle_rpm);
    px.push_back(s.e_proc_x_um);
    ux.push_back(s.u_e_proc_x_um);
    py.push_back(s.e_proc_y_um);
    uy.push_back(s.u_e_proc_y_um);
  }
  for (const auto& g : st.stages) {
    f.push_back(1000.0 * g.feed_mm_per_min / g.spindle_rpm);
    px.push_back(g.intercept_x_um());
    ux.push_back(g.one_part_x.u_pred_um);
    py.push_back(g.intercept_y_um());
    uy.push_back(g.one_part_y.u_pred_um);
  }
  const std::vector<Candidate> feed_forms{{Family::Polynomial, 1, true}, {Family::Polynomial, 2, true}, {Family::Hyperbolic, 0, false}};
  p.proc_x = fitSteppedComponent("e_proc_x_um", "chip_load_um_per_rev", f, px, ux, feed_forms, file);
  p.proc_y = fitSteppedComponent("e_proc_y_um", "chip_load_um_per_rev", f, py, uy, feed_forms, file);
  p.proc_per_rev = true;
  p.thermal = [st](double T, double S) {
    ThermalTerms t;
    const auto x = st.at(ThermalComponent::PtX, T, S), y = st.at(ThermalComponent::PtY, T, S), z = st.at(ThermalComponent::Splz, T, S);
    t.pt_x_um = x.value_um;
    t.pt_y_um = y.value_um;
    t.splz_um = z.value_um;
    t.U_pt_x_um = x.k95 * x.u_um;
    t.U_pt_y_um = y.k95 * y.u_um;
    t.U_splz_um = z.k95 * z.u_um;
    t.basis = x.basis;
    return t;
  };
  std::string speeds;
  for (const auto& s : st.stages) speeds += (speeds.empty() ? "" : ", ") + rpm(s.spindle_rpm);
  p.thermal_summary = "thermal stages at " + speeds + " (e_pt, e_splz interpolated linearly in S)";
  return p;
}

namespace {

json componentJson(const SteppedComponent& c, bool free_intercept) {
  const auto& best = c.selection.candidates[static_cast<std::size_t>(c.selection.best)];
  json j{{"name", c.name}, {"variable", c.variable}, {"form", best.candidate.label()}, {"formula", c.fit.function.formula()}};
  json params = json::object();
  for (std::size_t i = 0; i < c.fit.function.p.size() && i < c.fit.names.size(); ++i) params[c.fit.names[i]] = c.fit.function.p[i];
  j["parameters"] = params;
  if (free_intercept) j["intercept_um"] = c.fit.function.evaluate(0);
  j["loo_rms_um"] = best.loo_rms;
  j["u_um"] = c.u_pred_um;
  j["k95"] = c.k95;
  json pts = json::array();
  for (std::size_t i = 0; i < c.x.size(); ++i) pts.push_back({c.x[i], c.y[i], c.u[i]});
  j["points"] = pts;
  return j;
}

json valueJson(const ThermalValue& v) {
  return {{"value", v.value_um}, {"u_c", v.u_um}, {"k", v.k95}, {"U", v.k95 * v.u_um}, {"basis", v.basis}};
}

}  // namespace

std::string separationJson(const ThermalStages& st, const std::vector<ProcessStep>& process, const json* process_evaluation,
                           const std::string& process_file, const json* control) {
  json j{{"kind", "stepped_separation"}};
  j["interpolation"] =
      "linear in the spindle speed between the stages, the weight (S - S_a)/(S_b - S_a) on the faster stage b; outside the "
      "measured speeds the nearest stage x S/S_stage (seed 000 Eq. 3.9/3.10). The thesis's Eq. 3.7/3.8 (and Eq. 5.17, 5.18, "
      "5.21, 5.25, 5.26, 5.29, 5.30, 5.33, 5.34, 5.37, 5.41, 5.42) print the weights swapped: not used.";
  json stages = json::array();
  for (const auto& s : st.stages) {
    json js{{"spindle_rpm", s.spindle_rpm}, {"feed_mm_per_min", s.feed_mm_per_min}, {"experiments", s.experiments}, {"files", s.files}};
    js["e_pt_x_um"] = componentJson(s.one_part_x, true);
    js["e_pt_y_um"] = componentJson(s.one_part_y, true);
    js["e_splz_um"] = componentJson(s.splz, false);
    js["steps"] = s.steps;
    stages.push_back(js);
  }
  j["stages"] = stages;
  json ps = json::array();
  for (const auto& p : process) {
    ps.push_back({{"step", p.step}, {"feed_mm_per_min", p.feed_mm_per_min}, {"spindle_rpm", p.spindle_rpm},
                  {"temp_state_min", p.temp_state_min},
                  {"one_part_e_proc_x_um", {{"value", p.one_part_x_um}, {"u_c", p.u_one_part_x_um}}},
                  {"one_part_e_proc_y_um", {{"value", p.one_part_y_um}, {"u_c", p.u_one_part_y_um}}},
                  {"e_pt_x_um", valueJson(p.pt_x)}, {"e_pt_y_um", valueJson(p.pt_y)},
                  {"e_proc_x_um", {{"value", p.e_proc_x_um}, {"u_c", p.u_e_proc_x_um}, {"U", p.U_e_proc_x_um}}},
                  {"e_proc_y_um", {{"value", p.e_proc_y_um}, {"u_c", p.u_e_proc_y_um}, {"U", p.U_e_proc_y_um}}}});
  }
  j["process"] = ps;
  if (control) j["control"] = *control;
  if (process_evaluation) {
    j["process_file"] = process_file;
    j["process_evaluation"] = *process_evaluation;
  }
  j["stage_evaluations"] = st.sources;
  return j.dump(2) + "\n";
}

SeparationCampaign campaignFromSeparationJson(const json& j, const std::string& file) {
  if (!j.is_object() || j.value("kind", "") != "stepped_separation" || !j.contains("stage_evaluations") ||
      !j.at("stage_evaluations").is_array())
    throw InputError(file, 0, "kind: expected the separation.json of `probeloop separate` (stepped workpiece campaign)");
  std::vector<std::pair<json, std::string>> parts;
  for (const auto& s : j.at("stage_evaluations")) {
    if (!s.is_object() || !s.contains("evaluation")) throw InputError(file, 0, "stage_evaluations[]: expected {file, evaluation}");
    parts.emplace_back(s.at("evaluation"), file + ": stage_evaluations[" + s.value("file", "?") + "]");
  }
  SeparationCampaign c;
  c.stages = thermalStagesFromEvaluations(parts);
  if (j.contains("process_evaluation")) {
    c.process_evaluation = j.at("process_evaluation");
    c.process_file = j.value("process_file", file);
  }
  return c;
}

std::string separationCsv(const ThermalStages& st, const std::vector<ProcessStep>& process) {
  std::string s = "role,experiment,step,spindle_rpm,feed_mm_per_min,temp_state_min,one_part_e_proc_x_um,one_part_e_proc_y_um,"
                  "e_pt_x_um,U_e_pt_x_um,e_pt_y_um,U_e_pt_y_um,e_splz_um,U_e_splz_um,e_proc_x_um,U_e_proc_x_um,e_proc_y_um,U_e_proc_y_um\n";
  auto f = [](double v) { return formatNumber(v, 4); };
  for (const auto& g : st.stages) {
    for (std::size_t i = 0; i < g.one_part_x.x.size(); ++i) {
      const double T = g.one_part_x.x[i];
      const auto x = st.at(ThermalComponent::PtX, T, g.spindle_rpm), y = st.at(ThermalComponent::PtY, T, g.spindle_rpm),
                 z = st.at(ThermalComponent::Splz, T, g.spindle_rpm);
      // The stage's own process (and control) error: its intercept (L844).
      s += "stage," + g.point_experiments[i] + "," + std::to_string(g.steps[i]) + "," + f(g.spindle_rpm) + "," + f(g.feed_mm_per_min) + "," + f(T) + "," +
           f(g.one_part_x.y[i]) + "," + f(g.one_part_y.y[i]) + "," + f(x.value_um) + "," + f(x.k95 * x.u_um) + "," + f(y.value_um) + "," +
           f(y.k95 * y.u_um) + "," + f(z.value_um) + "," + f(z.k95 * z.u_um) + "," + f(g.intercept_x_um()) + "," +
           f(g.one_part_x.k95 * g.one_part_x.u_pred_um) + "," + f(g.intercept_y_um()) + "," + f(g.one_part_y.k95 * g.one_part_y.u_pred_um) + "\n";
    }
  }
  for (const auto& p : process) {
    const auto z = st.at(ThermalComponent::Splz, p.temp_state_min, p.spindle_rpm);
    s += "process," + p.experiment + "," + std::to_string(p.step) + "," + f(p.spindle_rpm) + "," + f(p.feed_mm_per_min) + "," + f(p.temp_state_min) + "," +
         f(p.one_part_x_um) + "," + f(p.one_part_y_um) + "," + f(p.pt_x.value_um) + "," + f(p.pt_x.k95 * p.pt_x.u_um) + "," +
         f(p.pt_y.value_um) + "," + f(p.pt_y.k95 * p.pt_y.u_um) + "," + f(z.value_um) + "," + f(z.k95 * z.u_um) + "," + f(p.e_proc_x_um) +
         "," + f(p.U_e_proc_x_um) + "," + f(p.e_proc_y_um) + "," + f(p.U_e_proc_y_um) + "\n";
  }
  return s;
}

std::string separationSummary(const ThermalStages& st, const std::vector<ProcessStep>& process) {
  std::string s = "Thermal stages of the stepped workpiece (" + std::to_string(st.stages.size()) + "):\n";
  for (const auto& g : st.stages) {
    std::string ex;
    for (const auto& e : g.experiments) ex += (ex.empty() ? "" : "+") + e;
    s += "  " + rpm(g.spindle_rpm) + " (" + ex + ", feed " + formatNumber(g.feed_mm_per_min) + " mm/min, " +
         std::to_string(g.one_part_x.x.size()) + " steps): process error at thermal zero X " + formatNumber(g.intercept_x_um(), 2) +
         ", Y " + formatNumber(g.intercept_y_um(), 2) + " um\n";
    for (const auto* c : {&g.one_part_x, &g.one_part_y, &g.splz}) s += "    " + steppedComponentSummary(*c) + "\n";
  }
  if (!process.empty()) {
    s += "Process error with the thermal error taken out (two walls, U):\n";
    for (const auto& p : process)
      s += "  step " + std::to_string(p.step) + " (F " + formatNumber(p.feed_mm_per_min) + ", T " + formatNumber(p.temp_state_min, 1) +
           " min): e_proc_x " + formatNumber(p.e_proc_x_um, 2) + " +- " + formatNumber(p.U_e_proc_x_um, 2) + " (one part " +
           formatNumber(p.one_part_x_um, 2) + ", e_pt " + formatNumber(p.pt_x.value_um, 2) + "), e_proc_y " + formatNumber(p.e_proc_y_um, 2) +
           " +- " + formatNumber(p.U_e_proc_y_um, 2) + " um\n";
  }
  return s;
}

}  // namespace probeloop::model
