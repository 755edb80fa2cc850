#include "uncertainty/text_model.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/error.hpp"

namespace probeloop::uncertainty {

TextModelResult evaluateTextModel(const TextModel& m, const std::optional<McmOptions>& options) {
  m.inputs.check();
  const std::size_t n = m.inputs.inputs.size();
  std::vector<double> x0(n);
  for (std::size_t i = 0; i < n; ++i) x0[i] = m.inputs.inputs[i].value;
  TextModelResult r;
  for (const auto& o : m.outputs) {
    Problem pr = m.inputs;
    pr.output = o.name;
    pr.unit = o.unit;
    std::vector<double> g(n);
    const double y = o.model.gradient(x0.data(), g);
    TextOutputResult tr;
    try {
      tr.guf = gufFromGradient(pr, y, g, m.p);
    } catch (const GeometryError& e) {
      throw InputError(m.file, o.line, std::string("outputs.") + o.name + ".model: " + e.what());
    }
    r.outputs.push_back(std::move(tr));
  }
  const auto k = static_cast<Eigen::Index>(m.outputs.size());
  r.correlation = Eigen::MatrixXd::Identity(k, k);
  for (Eigen::Index a = 0; a < k; ++a)
    for (Eigen::Index b = a + 1; b < k; ++b)
      r.correlation(a, b) = r.correlation(b, a) =
          outputCorrelation(m.inputs, r.outputs[static_cast<std::size_t>(a)].guf, r.outputs[static_cast<std::size_t>(b)].guf);
  if (!options) return r;

  // One draw of the inputs serves every output; the adaptive stop waits for all of them.
  McmOptions o = *options;
  o.p = m.p;
  try {
    detail::checkTrials(o);
  } catch (const InputError& e) {
    throw InputError(m.file, 0, e.what());
  }
  const long batch = detail::batchSize(o);
  const long limit = o.fixed_trials > 0 ? o.fixed_trials : o.max_trials;
  std::vector<std::vector<double>> all(m.outputs.size());
  std::vector<std::vector<McmResult>> batches(m.outputs.size());
  bool converged = false;
  long done = 0;
  while (done < limit) {
    const long b = std::min(batch, limit - done);
    std::vector<double> x;
    try {
      x = detail::sampleInputs(m.inputs, b, o.seed, done);
    } catch (const InputError& e) {
      throw InputError(m.file, 0, e.what());
    }
    bool all_stable = true;
    for (std::size_t j = 0; j < m.outputs.size(); ++j) {
      std::vector<double> y(static_cast<std::size_t>(b));
      for (long t = 0; t < b; ++t) {
        y[static_cast<std::size_t>(t)] = m.outputs[j].model.evaluate(&x[static_cast<std::size_t>(t) * n]);
        if (!std::isfinite(y[static_cast<std::size_t>(t)]))
          try {
            detail::nonFinite(m.outputs[j].name);
          } catch (const GeometryError& e) {
            throw InputError(m.file, m.outputs[j].line, std::string("outputs.") + e.what());
          }
      }
      all[j].insert(all[j].end(), y.begin(), y.end());
      if (o.fixed_trials == 0) {
        batches[j].push_back(detail::summarise(y, o.p));
        all_stable = all_stable && detail::stable(batches[j], o.significant_digits);
      }
    }
    done += b;
    if (o.progress) o.progress(done);
    if (o.fixed_trials == 0 && all_stable) {
      converged = true;
      break;
    }
  }
  r.mcm_trials = done;
  r.mcm_adaptive = o.fixed_trials == 0;
  r.mcm_converged = converged;
  for (std::size_t j = 0; j < m.outputs.size(); ++j) {
    McmResult mr = detail::summarise(all[j], o.p);
    mr.converged = converged;
    mr.delta = numericalTolerance(mr.u, o.significant_digits);
    r.outputs[j].mcm = mr;
    r.outputs[j].validation = validate(r.outputs[j].guf, mr, o.significant_digits);
  }
  return r;
}

namespace {

std::string g(double v, int digits = 6) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

std::string dof(double v) { return std::isfinite(v) ? g(v, 4) : "inf"; }

}  // namespace

std::string textModelReport(const TextModel& m, const TextModelResult& r) {
  std::ostringstream o;
  if (!m.title.empty()) o << m.title << "\n";
  o << "Coverage probability p = " << g(m.p) << "\n";
  for (std::size_t j = 0; j < m.outputs.size(); ++j) {
    const auto& out = m.outputs[j];
    const auto& res = r.outputs[j];
    const auto& gu = res.guf;
    o << "\n" << out.name << " = " << out.model.text() << (out.unit.empty() ? "" : "   [" + out.unit + "]") << "\n";
    o << "  GUM uncertainty budget (JCGM 100), largest contribution first:\n";
    char line[512];
    std::snprintf(line, sizeof line, "  %-28s %14s %12s %-12s %7s %13s %12s %7s\n", "input", "estimate", "u(x)",
                  "distribution", "dof", "c", "|c| u", "share");
    o << line;
    for (const auto& c : gu.budget.contributions) {
      std::size_t i = 0;
      while (i < m.inputs.inputs.size() && m.inputs.inputs[i].name != c.input) ++i;
      const auto& in = m.inputs.inputs[i];
      const double share = gu.u_c > 0 ? c.u * c.u / (gu.u_c * gu.u_c) * 100 : 0;
      char pct[16];
      std::snprintf(pct, sizeof pct, "%6.1f%%", share);
      std::snprintf(line, sizeof line, "  %-28s %14s %12s %-12s %7s %13s %12s %7s\n", in.name.c_str(),
                    g(in.value, 9).c_str(), g(in.gufU(), 4).c_str(), c.distribution.c_str(), dof(c.dof).c_str(),
                    g(gu.c[i], 5).c_str(), g(c.u, 4).c_str(), gu.correlated ? "-" : pct);
      o << line;
    }
    o << "  y = " << g(gu.y, 10) << "  u_c = " << g(gu.u_c, 4) << "  nu_eff = " << dof(gu.nu_eff)
      << "  k = " << g(gu.k, 4) << "  U = " << g(gu.U, 3) << "  interval [" << g(gu.y - gu.U, 8) << ", "
      << g(gu.y + gu.U, 8) << "]\n";
    if (gu.correlated)
      o << "  (inputs are correlated: u_c includes the covariance terms, so shares of u_c^2 are not defined; "
           "nu_eff is Welch-Satterthwaite, not below the smallest dof of the correlated inputs)\n";
    if (res.mcm) {
      const auto& mc = *res.mcm;
      const auto& v = *res.validation;
      o << "  Monte Carlo (JCGM 101), " << mc.trials << " trials"
        << (mc.converged ? " (adaptive stop reached)" : r.mcm_adaptive ? " (adaptive stop NOT reached: the results are not stable to the requested digits; the model may have a pole or an infinite variance)" : " (fixed)")
        << ": y = " << g(mc.y, 10) << "  u = " << g(mc.u, 4) << "\n";
      o << "    probabilistically symmetric interval [" << g(mc.symmetric_low, 8) << ", " << g(mc.symmetric_high, 8)
        << "], shortest [" << g(mc.shortest_low, 8) << ", " << g(mc.shortest_high, 8) << "]\n";
      o << "    validation of the GUF (JCGM 101 8): d_low = " << g(v.d_low, 3) << ", d_high = " << g(v.d_high, 3)
        << ", delta = " << g(v.delta, 3) << ": "
        << (!mc.converged && r.mcm_adaptive ? "no verdict: the Monte Carlo run did not converge"
            : v.validated                  ? "the GUF is validated; its interval may be used"
                                           : "the GUF is NOT validated; report the Monte Carlo interval")
        << "\n";
    }
  }
  if (m.outputs.size() > 1) {
    o << "\nCorrelation of the outputs (GUF):\n";
    for (std::size_t a = 0; a < m.outputs.size(); ++a) {
      o << "  " << m.outputs[a].name;
      for (std::size_t b = 0; b < m.outputs.size(); ++b) {
        char c[32];
        std::snprintf(c, sizeof c, " %+.3f", r.correlation(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)));
        o << c;
      }
      o << "\n";
    }
  }
  return o.str();
}

std::string textModelJson(const TextModel& m, const TextModelResult& r) {
  using nlohmann::ordered_json;
  ordered_json j;
  j["format"] = "probeloop-gum";
  j["version"] = 1;
  j["model_file"] = m.file;
  j["title"] = m.title;
  j["coverage_probability"] = m.p;
  for (const auto& in : m.inputs.inputs)
    j["inputs"].push_back({{"name", in.name},
                           {"unit", in.unit},
                           {"value", in.value},
                           {"u", in.gufU()},
                           {"distribution", distributionName(in.distribution)},
                           {"dof", std::isfinite(in.dof) ? ordered_json(in.dof) : ordered_json()},
                           {"type", std::string(1, in.type)}});
  for (std::size_t k = 0; k < m.outputs.size(); ++k) {
    const auto& gu = r.outputs[k].guf;
    ordered_json o;
    o["name"] = m.outputs[k].name;
    o["unit"] = m.outputs[k].unit;
    o["model"] = m.outputs[k].model.text();
    o["guf"] = {{"y", gu.y},
                {"u_c", gu.u_c},
                {"nu_eff", std::isfinite(gu.nu_eff) ? ordered_json(gu.nu_eff) : ordered_json()},
                {"k", gu.k},
                {"U", gu.U},
                {"interval", {gu.y - gu.U, gu.y + gu.U}},
                {"correlated_inputs", gu.correlated}};
    for (std::size_t i = 0; i < gu.c.size(); ++i)
      o["guf"]["sensitivities"][m.inputs.inputs[i].name] = gu.c[i];
    for (const auto& c : gu.budget.contributions)
      o["guf"]["budget"].push_back({{"input", c.input}, {"type", std::string(1, c.type)}, {"distribution", c.distribution}, {"u", c.u}});
    if (r.outputs[k].mcm) {
      const auto& mc = *r.outputs[k].mcm;
      const auto& v = *r.outputs[k].validation;
      o["mcm"] = {{"trials", mc.trials},
                  {"converged", mc.converged},
                  {"y", mc.y},
                  {"u", mc.u},
                  {"symmetric_interval", {mc.symmetric_low, mc.symmetric_high}},
                  {"shortest_interval", {mc.shortest_low, mc.shortest_high}}};
      o["validation"] = {{"d_low", v.d_low}, {"d_high", v.d_high}, {"delta", v.delta}, {"guf_validated", v.validated}};
    }
    j["outputs"].push_back(o);
  }
  if (m.outputs.size() > 1)
    for (Eigen::Index a = 0; a < r.correlation.rows(); ++a) {
      ordered_json row = ordered_json::array();
      for (Eigen::Index b = 0; b < r.correlation.cols(); ++b) row.push_back(r.correlation(a, b));
      j["output_correlation"].push_back(row);
    }
  return j.dump(1) + "\n";
}

}  // namespace probeloop::uncertainty
