#include "cli/model_commands.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>

#include "cli/input_option.hpp"
#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/input_file.hpp"
#include "parts/json_file.hpp"
#include "model/diagnose.hpp"
#include "model/stepped_series.hpp"
#include "model/outputs.hpp"
#include "model/talc.hpp"
#include "cli/talc_options.hpp"
#include "parts/error_model_file.hpp"
#include "parts/piece_kinds.hpp"
#include "report/model_report.hpp"

namespace probeloop::cli {
using parts::readJsonFile;
namespace fs = std::filesystem;

namespace {

struct ModelArgs {
  std::vector<std::string> models;
  std::string inputs, errors, html, part;
  bool json = false;
  // add
  std::string kind, model, channels, input, lever;
  std::optional<double> tau_s, alpha, length_mm;
  bool tau_fixed = false;
  // talc
  model::TalcOptions talc;
  std::string talc_inputs;
  // series
  std::vector<std::string> series_parts;  // evaluation.json, inputs.csv, evaluation.json, ...
  std::string out = "series";
  int train_parts = 0;
  std::string start_from;
  double gap_h = 24;
};

std::string resolve(const std::string& model_file, const std::string& p) {
  if (p.empty() || fs::path(p).is_absolute()) return p;
  return (fs::path(model_file).parent_path() / p).lexically_normal().string();
}

model::Campaign campaignFor(const model::ErrorModel& m, const ModelArgs& a) {
  const std::string in = a.inputs.empty() ? resolve(m.file, m.inputs_path) : a.inputs;
  const std::string er = a.errors.empty() ? resolve(m.file, m.errors_path) : a.errors;
  if (in.empty() || er.empty())
    throw InputError(m.file, 0, "no data: give --inputs and --errors, or data: {inputs: ..., errors: ...} in the model file");
  return model::loadCampaign(in, er);
}

std::optional<model::ExpansionLevers> expansionLevers(const std::string& part) {
  if (part.empty()) return std::nullopt;
  return parts::expansionLevers(parts::loadTestPiece(part));
}

// "Wrote" goes to stderr when stdout carries JSON.
void writeReport(const std::string& path, const nlohmann::json& fit, const nlohmann::json* diag, bool json) {
  if (path.empty()) return;
  writeFileAtomic(path, report::modelReportHtml(fit, diag));
  std::fprintf(json ? stderr : stdout, "%sWrote %s\n", json ? "" : "\n", path.c_str());
}

int runFit(const ModelArgs& a) {
  const auto m = parts::loadErrorModel(a.models.front());
  const auto c = campaignFor(m, a);
  const auto f = model::fitModel(c, m);
  const auto j = model::fitJson(c, m, f);
  std::fputs(a.json ? (j.dump(1) + "\n").c_str() : model::fitText(c, m, f).c_str(), stdout);
  writeReport(a.html, j, nullptr, a.json);
  return 0;
}

int runCompare(const ModelArgs& a) {
  std::vector<model::ErrorModel> ms;
  for (const auto& p : a.models) ms.push_back(parts::loadErrorModel(p));
  const auto c = campaignFor(ms.front(), a);
  std::vector<model::ModelFit> fits;
  for (const auto& m : ms) fits.push_back(model::fitModel(c, m, ms.front().training_fraction));
  std::fputs(a.json ? (model::compareJson(c, ms, fits).dump(1) + "\n").c_str() : model::compareText(c, ms, fits).c_str(), stdout);
  return 0;
}

int runDiagnose(const ModelArgs& a) {
  const auto m = parts::loadErrorModel(a.models.front());
  const auto c = campaignFor(m, a);
  model::DiagnoseOptions opt;
  opt.levers = expansionLevers(a.part);
  opt.part_path = a.part;
  opt.model_path = a.models.front();
  const auto d = model::diagnose(c, m, opt);
  const auto dj = model::diagnosisJson(c, m, d);
  std::fputs(a.json ? (dj.dump(1) + "\n").c_str() : model::diagnosisText(c, m, d).c_str(), stdout);
  if (!a.html.empty()) {
    model::ModelFit f;
    f.after = d.fits;
    f.train_end = model::trainingEnd(c.errors.size(), m.training_fraction);
    writeReport(a.html, model::fitJson(c, m, f), &dj, a.json);
  }
  return 0;
}

int runAdd(const ModelArgs& a) {
  auto m = parts::loadErrorModel(a.model);
  const auto kind = model::kindFromName(a.kind);
  if (!kind || *kind == model::EffectKind::Offset)
    throw InputError("", 0, "model add: unknown effect '" + a.kind + "'; the effects are drift, static, lag, transient, expansion, force");
  std::vector<std::string> chans;
  std::stringstream ss(a.channels);
  for (std::string s; std::getline(ss, s, ',');) {
    const auto b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
    if (b == std::string::npos) continue;
    s = s.substr(b, e - b + 1);
    if (s.find_first_of(" \t:#{}[],'\"") != std::string::npos)
      throw InputError("", 0, "model add: '" + s + "' is not a channel name (as in errors.csv, e.g. EY0C_um)");
    chans.push_back(s);
  }
  if (chans.empty()) throw InputError("", 0, "model add: --channels lists no channel");
  // Checked against the model's data before anything is written: a channel or input that the
  // data lack would only fail at the next fit, and "EY0C" for "EY0C_um" would be fitted twice.
  std::string checked = "(not checked: the model file names no data)";
  if (!m.inputs_path.empty() && !m.errors_path.empty()) {
    const auto c = campaignFor(m, a);
    auto list = [](const std::vector<std::string>& v) {
      std::string s;
      for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
      return s;
    };
    for (auto& name : chans) {
      const int k = c.errors.channel(name);
      if (k < 0)
        throw InputError(a.model, 0, "model add: no channel '" + name + "' in " + c.errors.file + "; its channels: " +
                                         list(c.errors.channels));
      if (c.errors.channels[static_cast<size_t>(k)] != name) {
        std::printf("Channel %s is %s in %s.\n", name.c_str(), c.errors.channels[static_cast<size_t>(k)].c_str(),
                    c.errors.file.c_str());
        name = c.errors.channels[static_cast<size_t>(k)];
      }
    }
    for (const auto* in : {&a.input, &a.lever})
      if (!in->empty() && c.inputs.column(*in) < 0)
        throw InputError(a.model, 0, "model add: no input '" + *in + "' in " + c.inputs.file + "; its inputs: " +
                                         list(c.inputs.names));
    checked = "(checked against " + c.errors.file + " and " + c.inputs.file + ")";
  }
  model::Effect e = model::makeEffect(*kind, a.input);
  if (*kind == model::EffectKind::Drift && !a.input.empty())
    throw InputError("", 0, "model add drift: a drift reads no input; leave out --input");
  if (*kind != model::EffectKind::Drift && a.input.empty())
    throw InputError("", 0, "model add " + a.kind + ": needs --input (an inputs.csv column)");
  if (!a.lever.empty()) {
    if (*kind != model::EffectKind::Static && *kind != model::EffectKind::Lag)
      throw InputError("", 0, "model add " + a.kind + ": --lever is for a static or lag effect");
    e.lever = a.lever;
  }
  if (e.hasTimeConstant()) {
    e.tau_s = a.tau_s;
    e.tau_fixed = a.tau_fixed;
    if (e.tau_fixed && !e.tau_s) throw InputError("", 0, "model add: --tau-fixed needs --tau-s");
  }
  const auto levers = expansionLevers(a.part);
  for (auto& c : m.channels)
    for (auto& x : c.effects) x.just_added = false;
  std::vector<std::string> created;
  for (const auto& name : chans) {
    model::Effect ce = e;
    ce.just_added = true;
    if (*kind == model::EffectKind::Expansion) {
      ce.alpha_um_per_m_K = a.alpha ? *a.alpha : levers ? levers->alpha_um_per_m_K : 0;
      ce.length_mm = a.length_mm ? *a.length_mm : levers ? levers->lengthFor(name).value_or(0) : 0;
      if (!(ce.alpha_um_per_m_K > 0 && ce.length_mm != 0))
        throw InputError("", 0, "model add expansion on " + name +
                                    ": needs --part (a sphere artifact: EZ0T uses its height, ER0T its radius from the C axis; "
                                    "a thermal test piece: EZ the Z paths' height, ETTP -2 x the facets' apothem) "
                                    "or --alpha-um-per-m-K and --length-mm");
    }
    auto it = std::find_if(m.channels.begin(), m.channels.end(), [&](const model::ChannelModel& c) { return c.channel == name; });
    if (it == m.channels.end()) {
      m.channels.push_back({name, {}});
      it = std::prev(m.channels.end());
      created.push_back(name);
    }
    for (const auto& have : it->effects)
      if (have.id() == ce.id()) throw InputError(a.model, 0, "channels." + name + ": already has " + ce.id());
    it->effects.push_back(ce);
  }
  const auto patched = parts::patchErrorModelText(readFile(a.model, kYamlInput), m);
  if (patched) writeFileAtomic(a.model, *patched);
  else parts::saveErrorModel(m, a.model);
  std::string names;
  for (const auto& n : chans) names += (names.empty() ? "" : ",") + n;
  std::printf("Added %s to %s in %s %s", e.id().c_str(), names.c_str(), a.model.c_str(), checked.c_str());
  if (!created.empty()) std::printf(" (new channels: %zu)", created.size());
  std::printf(".\n%s Next, to see before and after:\n  probeloop model fit %s\n",
              patched ? "The file keeps its comments and layout; the new lines are marked just_added."
                      : "The file was rewritten in canonical form (its layout was not one model add edits in place; comments are not kept).",
              a.model.c_str());
  return 0;
}

int runTalc(const ModelArgs& a) {
  if (a.inputs.empty() || a.errors.empty()) throw InputError("", 0, "model talc: give --inputs and --errors");
  const auto c = model::loadCampaign(a.inputs, a.errors);
  model::TalcOptions o = a.talc;
  o.inputs = talcInputsFrom(a.talc_inputs);
  const auto r = model::replayTalc(c, o);
  std::fputs(model::talcText(r).c_str(), stdout);
  return 0;
}

int runSeries(const ModelArgs& a) {
  std::vector<model::SteppedSeriesPart> parts;
  for (std::size_t i = 0; i + 1 < a.series_parts.size(); i += 2)
    parts.push_back({readJsonFile(a.series_parts[i]), a.series_parts[i], model::loadInputs(a.series_parts[i + 1])});
  if (!std::isfinite(a.gap_h) || a.gap_h < 0) throw InputError("", 0, "model series: --gap-h must be a finite number of hours >= 0");
  const auto s = model::buildSteppedSeries(parts, a.gap_h * 3600.0, a.train_parts);
  // --start-from: a grown campaign goes on from the model the last loop ended with (its effects,
  // the new series' data and split).
  std::string model_yaml = s.model_yaml;
  if (!a.start_from.empty()) {
    auto em = parts::loadErrorModel(a.start_from);
    for (const auto& c : em.channels)
      if (c.channel != "width_x_um" && c.channel != "width_y_um" && c.channel != "depth_um")
        throw InputError(a.start_from, 0, "channel " + c.channel + ": the stepped series has width_x_um, width_y_um and depth_um");
    for (auto& c : em.channels)
      for (auto& e : c.effects) e.just_added = false;
    em.inputs_path = "inputs.csv";
    em.errors_path = "errors.csv";
    em.training_fraction = s.training_fraction;
    model_yaml = parts::errorModelYaml(em);
  }
  fs::create_directories(a.out);
  writeFileAtomic((fs::path(a.out) / "inputs.csv").string(), s.inputs_csv);
  writeFileAtomic((fs::path(a.out) / "errors.csv").string(), s.errors_csv);
  writeFileAtomic((fs::path(a.out) / "model.yaml").string(), model_yaml);
  std::fputs(s.summary.c_str(), stdout);
  std::printf("  wrote inputs.csv, errors.csv and model.yaml (%s) in %s\n",
              a.start_from.empty() ? "position error only" : ("the effects of " + a.start_from).c_str(), a.out.c_str());
  return 0;
}

}  // namespace

std::function<int()> addModelCommands(CLI::App& app, CLI::App*& group) {
  auto a = std::make_shared<ModelArgs>();
  group = app.add_subcommand("model", "Error models against measurements: fit, compare, diagnose, add an effect");
  group->require_subcommand(1);
  auto data = [a](CLI::App* s) {
    s->add_option("--inputs", a->inputs, "inputs.csv of the campaign (default: data.inputs of the model file)")->check(cli::inputFile());
    s->add_option("--errors", a->errors, "errors.csv of the campaign (default: data.errors of the model file)")->check(cli::inputFile());
    s->add_flag("--json", a->json, "print the results as JSON instead of the text");
  };
  auto* fit = group->add_subcommand("fit", "Fit the model on the training span, predict the validation span, report the indicators");
  fit->add_option("model", a->models, "error model (YAML, kind: error_model)")->required()->expected(1)->check(cli::inputFile());
  data(fit);
  fit->add_option("--html", a->html, "also write the HTML report to this file");
  auto* cmp = group->add_subcommand("compare", "Several models on the same campaign, side by side");
  cmp->add_option("models", a->models, "error models (YAML)")->required()->expected(1, 20)->check(cli::inputFile());
  data(cmp);
  auto* dia = group->add_subcommand("diagnose", "Where the model fails and which effect is missing, ranked, with the command that adds it");
  dia->add_option("model", a->models, "error model (YAML)")->required()->expected(1)->check(cli::inputFile());
  data(dia);
  dia->add_option("--part", a->part, "the test piece (YAML: sphere artifact, thermal test piece): enables its expansion candidates")->check(cli::inputFile());
  dia->add_option("--html", a->html, "also write the HTML report to this file");
  auto* add = group->add_subcommand("add", "Add an effect to channels of a model file (marked just_added: the next fit shows before and after)");
  add->add_option("effect", a->kind, "drift, static, lag, transient, expansion or force")
      ->required()->check(CLI::IsMember({"drift", "static", "lag", "transient", "expansion", "force"}));
  add->add_option("--model", a->model, "error model file to edit")->required()->check(cli::inputFile());
  add->add_option("--channels", a->channels, "comma-separated channels, e.g. EY0C_um,EZ0T_um")->required();
  add->add_option("--input", a->input, "inputs.csv column the effect reads");
  add->add_option("--lever", a->lever, "static/lag: an inputs column the effect acts over (lag spindle_rpm --lever travel_mm: a thermal scale error)");
  add->add_option("--tau-s", a->tau_s, "lag/transient: time constant to start from, s")->check(CLI::PositiveNumber);
  add->add_flag("--tau-fixed", a->tau_fixed, "keep the time constant fixed");
  add->add_option("--part", a->part, "expansion: the test piece (YAML) giving alpha and the levers")->check(cli::inputFile());
  add->add_option("--alpha-um-per-m-K", a->alpha, "expansion: coefficient")->check(CLI::PositiveNumber);
  add->add_option("--length-mm", a->length_mm, "expansion: signed lever L of alpha L dT, mm");
  auto* talc = group->add_subcommand("talc", "Adaptive replay of seed 004 Ch. 6 (TALC) over a densely measured campaign: P99 reduction as Tables 6.5/6.7");
  talc->add_option("--inputs", a->inputs, "inputs.csv of the campaign")->required()->check(cli::inputFile());
  talc->add_option("--errors", a->errors, "errors.csv of the campaign (measured densely)")->required()->check(cli::inputFile());
  addTalcOptions(talc, a->talc, a->talc_inputs);
  talc->add_option("--cycle-duration-s", a->talc.cycle_duration_s, "duration of one measurement cycle, s (Q_Prod, Eq. 6.1)")->capture_default_str()->check(CLI::PositiveNumber);
  talc->add_flag("--include-cp", a->talc.include_cp, "P99 over the whole campaign, not only after the CP");
  auto* series = group->add_subcommand("series", "Stepped workpiece: several parts' evaluations and logged inputs -> one campaign "
                                       "(inputs.csv, errors.csv, a position-only model.yaml) for fit, diagnose and add");
  series->add_option("--part", a->series_parts, "a part's evaluation.json and its machine's inputs.csv (repeat, in cut order)")
      ->required()->type_size(2)->allow_extra_args(false)->check(cli::inputFile());
  series->add_option("--gap-h", a->gap_h, "hours the machine stands between two parts")->capture_default_str()->check(CLI::NonNegativeNumber);
  series->add_option("--train-parts", a->train_parts, "the first N parts train, the rest validate (default: the first 60 % of the steps)")
      ->check(CLI::PositiveNumber);
  series->add_option("--start-from", a->start_from, "model.yaml whose effects the new model starts from (default: the position error only)")
      ->check(cli::inputFile());
  series->add_option("--out", a->out, "output folder")->capture_default_str();
  return [a, fit, cmp, dia, add, talc, series]() -> int {
    if (*series) return runSeries(*a);
    if (*talc) return runTalc(*a);
    if (*fit) return runFit(*a);
    if (*cmp) return runCompare(*a);
    if (*dia) return runDiagnose(*a);
    if (*add) return runAdd(*a);
    return 2;
  };
}

}  // namespace probeloop::cli
