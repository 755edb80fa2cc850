#include "model/stepped_series.hpp"

#include <cmath>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "model/effects.hpp"
#include "model/stepped_evaluation_json.hpp"

namespace probeloop::model {

using nlohmann::json;

namespace {

struct StepRow {
  double t_s = 0;  // on the combined clock
  double width_x = 0, width_y = 0, depth = 0, U_x = 0, U_y = 0, U_z = 0;
};

struct StepCondition {
  double start_s = 0;  // on the combined clock
  double travel = 0, depth = 0, feed = 0, feed_per_rev = 0, transition_feed = 0;
};

bool isEventOrSwitch(const std::string& c) { return c == "tool_changes" || c == "mwf_on"; }


}  // namespace

SteppedSeries buildSteppedSeries(const std::vector<SteppedSeriesPart>& parts, double gap_s, int training_parts) {
  if (parts.empty()) throw InputError("", 0, "model series: no parts given");
  if (training_parts < 0 || training_parts >= static_cast<int>(parts.size()))
    throw InputError("", 0, "model series: --train-parts " + std::to_string(training_parts) + ": between 1 and " +
                                std::to_string(parts.size() - 1) + " (of the " + std::to_string(parts.size()) +
                                " parts given, at least one must validate)");
  int training_rows = 0;
  const auto& names = parts.front().inputs.names;
  const double step = parts.front().inputs.step_s;
  std::vector<double> t_all;
  std::vector<std::vector<double>> cols(names.size());
  std::vector<StepRow> rows;
  std::vector<StepCondition> conds;
  std::ostringstream comment;
  double offset = 0;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const auto& part = parts[p];
    const auto& in = part.inputs;
    const std::string& file = part.evaluation_file;
    requireSteppedEvaluation(part.evaluation, file);
    if (in.names != names)
      throw InputError(in.file, 0, "columns differ from " + parts.front().inputs.file + "'s: one campaign needs one logger");
    if (std::fabs(in.step_s - step) > 1e-9)
      throw InputError(in.file, 0, "logged every " + formatNumber(in.step_s) + " s, " + parts.front().inputs.file + " every " +
                                       formatNumber(step) + " s");
    if (p > 0) {
      // The gap: whole steps from the last sample, then this part's first sample one step later.
      const double last_t = t_all.back();
      const long n_gap = std::lround(std::ceil(gap_s / step));
      const double next_t = last_t + (n_gap + 1) * step;
      std::vector<double> last(names.size());
      for (std::size_t c = 0; c < names.size(); ++c) last[c] = cols[c].back();
      for (long k = 1; k <= n_gap; ++k) {
        const double f = static_cast<double>(k) / (n_gap + 1);
        t_all.push_back(last_t + k * step);
        for (std::size_t c = 0; c < names.size(); ++c) {
          const bool off = isSpeedInput(names[c]) || isEventOrSwitch(names[c]);
          cols[c].push_back(off ? 0.0 : last[c] * (1 - f) + in.columns[c].front() * f);
        }
      }
      offset = next_t - in.t_s.front();
    } else {
      offset = -in.t_s.front();
    }
    for (std::size_t k = 0; k < in.t_s.size(); ++k) {
      t_all.push_back(in.t_s[k] + offset);
      for (std::size_t c = 0; c < names.size(); ++c) cols[c].push_back(in.columns[c][k]);
    }
    // The moves that join the walls (evaluation.json's transition): their feed winds the drives
    // up (the thesis's control error, Sec. 3.6.2); a continuous path has none.
    if (!part.evaluation.contains("transition"))
      throw InputError(file, 0, "transition: missing (an evaluation.json written before the control separation: run evaluate again)");
    const std::string transition = part.evaluation.at("transition").is_string() ? part.evaluation.at("transition").get<std::string>() : "";
    const double transition_feed =
        transition == "continuous" ? 0.0 : evaluationNumber(part.evaluation, "transition_feed_mm_per_min", "", file);
    const auto& seps = part.evaluation.at("separation");
    const auto& cmm = part.evaluation.contains("cmm") ? part.evaluation.at("cmm").value("steps", json::array()) : json::array();
    if (cmm.size() != seps.size()) throw InputError(file, 0, "cmm.steps: " + std::to_string(cmm.size()) + " steps, separation " + std::to_string(seps.size()));
    for (std::size_t i = 0; i < seps.size(); ++i) {
      const auto& s = seps[i];
      const auto& g = cmm[i];
      const std::string where = "separation[" + std::to_string(i) + "].";
      const std::string gw = "cmm.steps[" + std::to_string(i) + "].";
      if (!s.contains("cut_mid_s"))
        throw InputError(file, 0, where + "cut_mid_s: missing (evaluate the part again: the series needs its cut times)");
      const double mid = evaluationNumber(s, "cut_mid_s", where, file);
      if (mid < in.t_s.front() || mid > in.t_s.back())
        throw InputError(file, 0, where + "cut_mid_s: " + formatNumber(mid, 1) + " s lies outside " + in.file + " (" +
                                      formatNumber(in.t_s.front(), 1) + " - " + formatNumber(in.t_s.back(), 1) + " s): not this part's log");
      StepRow r;
      r.t_s = mid + offset;
      r.width_x = evaluationNumber(g, "width_x_error_um", gw, file);
      r.width_y = evaluationNumber(g, "width_y_error_um", gw, file);
      r.depth = evaluationNumber(g, "depth_error_um", gw, file);
      // A compensated part was cut off nominal on purpose (walls in, floors up): the machine's
      // error is the CMM's plus the offsets (evaluation.json's compensation_applied).
      if (part.evaluation.contains("compensation_applied")) {
        const auto& ca = part.evaluation.at("compensation_applied");
        if (!ca.is_array() || ca.size() != seps.size())
          throw InputError(file, 0, "compensation_applied: one entry per step expected");
        const std::string cw = "compensation_applied[" + std::to_string(i) + "].";
        if (!ca[i].contains("wall_um")) throw InputError(file, 0, cw + "wall_um: missing");
        const auto& w = ca[i].at("wall_um");
        r.width_x += evaluationNumber(w, "XP", cw + "wall_um.", file) + evaluationNumber(w, "XN", cw + "wall_um.", file);
        r.width_y += evaluationNumber(w, "YP", cw + "wall_um.", file) + evaluationNumber(w, "YN", cw + "wall_um.", file);
        r.depth += evaluationNumber(ca[i], "floor_um", cw, file);
      }
      r.U_x = 2 * evaluationNumber(s, "u_cmm_width_x_um", where, file);
      r.U_y = 2 * evaluationNumber(s, "u_cmm_width_y_um", where, file);
      r.U_z = 2 * evaluationNumber(s, "u_cmm_depth_um", where, file);
      rows.push_back(r);
      StepCondition c;
      c.start_s = evaluationNumber(s, "cut_start_s", where, file) + offset;
      c.travel = evaluationNumber(s, "travel_tool_mm", where, file);
      c.depth = evaluationNumber(g, "depth_nominal_mm", gw, file);
      c.feed = evaluationNumber(s, "feed_mm_per_min", where, file);
      const double S = evaluationNumber(s, "spindle_rpm", where, file);
      if (!(S > 0)) throw InputError(file, 0, where + "spindle_rpm: must be positive (the feed per revolution divides by it)");
      c.feed_per_rev = 1000.0 * c.feed / S;
      c.transition_feed = transition_feed;
      conds.push_back(c);
    }
    if (static_cast<int>(p) < training_parts) training_rows = static_cast<int>(rows.size());
    comment << "# part " << p + 1 << ": " << file << " (" << part.evaluation.value("experiment", "?") << "), inputs " << in.file
            << " shifted by " << formatNumber(offset, 1) << " s\n";
  }
  // Rows must be in time order (parts in the given order, steps in cut order).
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (!(rows[i].t_s > rows[i - 1].t_s)) throw InputError(parts.front().evaluation_file, 0, "the steps' cut times are not increasing");

  SteppedSeries out;
  out.rows = static_cast<int>(rows.size());
  std::ostringstream in;
  in << "time_s";
  for (const auto& n : names) in << "," << n;
  in << ",travel_mm,depth_mm,cut_feed_mm_per_min,chip_load_um_per_rev,transition_feed_mm_per_min\n";
  std::size_t c = 0;
  for (std::size_t k = 0; k < t_all.size(); ++k) {
    while (c + 1 < conds.size() && conds[c + 1].start_s <= t_all[k]) ++c;
    in << formatNumber(t_all[k], 3);
    for (const auto& col : cols) in << "," << formatNumber(col[k], 4);
    const auto& s = conds[c];
    in << "," << formatNumber(s.travel, 3) << "," << formatNumber(s.depth, 3) << "," << formatNumber(s.feed, 1) << "," << formatNumber(s.feed_per_rev, 4) << ","
       << formatNumber(s.transition_feed, 1) << "\n";
  }
  out.inputs_csv = in.str();
  std::ostringstream er;
  er << "# the stepped workpiece's CMM errors per step at the mid-time of its wall cuts (probeloop model series)\n" << comment.str();
  er << "time_s,cycle,width_x_um,width_y_um,depth_um,U_width_x_um,U_width_y_um,U_depth_um\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    er << formatNumber(r.t_s, 3) << "," << i + 1 << "," << formatNumber(r.width_x, 4) << "," << formatNumber(r.width_y, 4) << "," << formatNumber(r.depth, 4) << ","
       << formatNumber(r.U_x, 4) << "," << formatNumber(r.U_y, 4) << "," << formatNumber(r.U_z, 4) << "\n";
  }
  out.errors_csv = er.str();
  // The first N parts train (trainingEnd rounds fraction x rows back to training_rows).
  const std::string fraction = training_parts > 0 ? formatNumber(static_cast<double>(training_rows) / rows.size(), 6) : "0.6";
  out.training_fraction = std::stod(fraction);
  out.model_yaml =
      "# The starting model of the stepped workpiece's loop: the position error only (seed 000 §9.1 item 10).\n"
      "# `probeloop model diagnose` names what is missing; `probeloop model add` adds it.\n"
      "kind: error_model\n"
      "data: {inputs: inputs.csv, errors: errors.csv}\n"
      "training_fraction: " + fraction + "\n"
      "channels:\n"
      "  width_x_um: [{effect: static, input: travel_mm}]\n"
      "  width_y_um: [{effect: static, input: travel_mm}]\n"
      "  depth_um: [{effect: static, input: depth_mm}]\n";
  out.summary = "Stepped series: " + std::to_string(parts.size()) + " parts, " + std::to_string(rows.size()) + " steps, " +
                std::to_string(t_all.size()) + " input samples every " + formatNumber(step) + " s (" +
                formatNumber((t_all.back() - t_all.front()) / 3600.0, 1) + " h with " + formatNumber(gap_s / 3600.0, 1) +
                " h between parts)\n";
  return out;
}

}  // namespace probeloop::model
