#include "campaign/live_loop.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "geometry/location_errors.hpp"

namespace probeloop::campaign {
namespace {

using model::TalcPhase;
using Json = nlohmann::ordered_json;

bool isModelEvent(const std::string& action) {
  return action.rfind("first fit", 0) == 0 || action.rfind("update after NG", 0) == 0 ||
         action.rfind("periodic update", 0) == 0;
}

Json modelsJson(const model::TalcController& tc) {
  Json out = Json::array();
  for (std::size_t q = 0; q < tc.models().size(); ++q) {
    const auto& m = tc.models()[q];
    Json c;
    c["channel"] = tc.channels()[q];
    Json theta = Json::object();
    for (Eigen::Index i = 0; i < m.theta.size(); ++i) theta[m.names[static_cast<std::size_t>(i)]] = m.theta(i);
    c["theta"] = theta;
    c["sigma"] = m.sigma;
    c["rows"] = m.rows;
    out.push_back(c);
  }
  return out;
}

}  // namespace

std::string liveOptionsJson(const LiveOptions& o) {
  const auto& t = o.talc;
  Json j;
  j["cp_h"] = t.cp_h;
  j["post_interval_h"] = t.post_interval_h;
  j["ng_interval_min"] = t.ng_interval_min;
  j["ng_measurements"] = t.ng_measurements;
  j["update_interval_h"] = t.update_interval_h;
  j["limit_linear_um"] = t.limit_linear_um;
  j["limit_angular_urad"] = t.limit_angular_urad;
  j["na"] = t.na;
  j["nb"] = t.nb;
  j["nb_per_input"] = t.nb_per_input;
  j["instantaneous"] = t.instantaneous;
  j["intercept"] = t.intercept;
  j["predicted_weight"] = t.predicted_weight;
  j["weight_half_life_h"] = t.weight_half_life_h;
  j["inputs"] = t.inputs;
  j["channels"] = t.channels;
  j["grid_s"] = o.grid_s;
  j["offsets_applied"] = o.offsets_applied;
  j["requested_only"] = o.requested_only;
  return j.dump();
}

LiveLoop::LiveLoop(CampaignStore& store, const LiveOptions& o) : store_(store), o_(o) {
  store_.upgradeToLiveSchema();
  Database& db = store_.database();
  const auto& m = store_.manifest();
  if (o_.grid_s <= 0) {
    if (m.cycle_start_s.size() < 2)
      throw InputError(db.path(), 0, "the plan has a single cycle: give the live loop its prediction grid (--grid-s)");
    o_.grid_s = m.cycle_start_s[1] - m.cycle_start_s[0];
  }
  grid_s_ = o_.grid_s;
  cycle_time_s_ = m.cycle_time_s;
  for (const char* n : geometry::LocationErrors::names()) channels_.push_back(n);
  if (!o_.talc.channels.empty()) {
    std::vector<std::string> chosen;
    for (const auto& c : o_.talc.channels) {
      const auto it = std::find_if(channels_.begin(), channels_.end(),
                                   [&](const std::string& n) { return n == c || n.rfind(c + "_", 0) == 0; });
      if (it == channels_.end())
        throw InputError(db.path(), 0, "TALC channel '" + c + "' is not a location error (EX0C_um ... EC0C_urad)");
      chosen.push_back(*it);
    }
    channels_ = chosen;
  }
  // The options are the campaign's: stored once, the same on every later run.
  const std::string json = liveOptionsJson(o_);
  {
    auto q = db.prepare("SELECT json FROM talc_config WHERE id = 1");
    if (q.step()) {
      const Json was = Json::parse(q.text(0)), now = Json::parse(json);
      for (auto it = was.begin(); it != was.end(); ++it)
        if (!now.contains(it.key()) || now[it.key()] != it.value())
          throw InputError(db.path(), 0, "this campaign's live loop runs with " + it.key() + " = " + it.value().dump() +
                                             ", not " + (now.contains(it.key()) ? now[it.key()].dump() : "(absent)") +
                                             ": the TALC options are fixed for a campaign (start a new store to change them)");
    } else {
      Transaction tx(db);
      db.prepare("INSERT INTO talc_config (id, json) VALUES (1, ?)").bind(1, json).run();
      tx.commit();
    }
  }
  // Rebuild the state from the steps already in the store, writing nothing.
  {
    auto q = db.prepare("SELECT COUNT(*) FROM talc_ticks");
    q.step();
    stored_ticks_ = static_cast<int>(q.integer(0));
    auto c = db.prepare("SELECT cycle FROM talc_measurements ORDER BY cycle");
    while (c.step()) stored_cycles_.push_back(static_cast<int>(c.integer(0)));
    auto ch = db.prepare("SELECT input, after_steps FROM talc_input_changes ORDER BY seq");
    while (ch.step()) changes_.push_back({ch.text(0), static_cast<int>(ch.integer(1))});
    auto e = db.prepare("SELECT COUNT(*) FROM talc_events");
    e.step();
    const auto stored_events = static_cast<std::size_t>(e.integer(0));
    run(false, false, nullptr);
    if (next_tick_ != stored_ticks_ || done_measurements_.size() != stored_cycles_.size() ||
        events_recorded_ != stored_events)
      throw InputError(db.path(), 0, "the live loop's stored steps (" + std::to_string(stored_ticks_) + " grid steps, " +
                                         std::to_string(stored_cycles_.size()) + " measurements, " +
                                         std::to_string(stored_events) + " events) cannot be replayed from the store's "
                                         "data (got " + std::to_string(next_tick_) + ", " +
                                         std::to_string(done_measurements_.size()) + ", " +
                                         std::to_string(events_recorded_) + "): the store was changed by hand");
    stored_ticks_ = -1;  // from here on, every step is new
    stored_cycles_.clear();
  }
}

LiveLoop::~LiveLoop() = default;

void requestLiveInput(CampaignStore& store, const std::string& name) {
  store.upgradeToLiveSchema();
  Database& db = store.database();
  model::InputSeries header;
  {
    auto h = db.prepare("SELECT header FROM input_source WHERE id = 1");
    if (!h.step()) throw InputError(db.path(), 0, "no inputs stream ingested yet: nothing to add " + name + " from");
    header.names = csvHeaderFields(h.text(0) + "\n");
    header.file = db.path() + " (inputs)";
  }
  const model::TalcInputColumns c = model::resolveTalcInputs(header, {name});  // InputError when absent
  std::vector<std::string> used;
  {
    auto q = db.prepare("SELECT json FROM talc_config WHERE id = 1");
    if (q.step()) used = Json::parse(q.text(0)).value("inputs", std::vector<std::string>{});
  }
  if (used.empty())
    for (const auto& l : model::resolveTalcInputs(header, {}).labels) used.push_back(l);
  else
    used = model::resolveTalcInputs(header, used).labels;
  auto q = db.prepare("SELECT label FROM talc_input_changes");
  while (q.step()) used.push_back(q.text(0));
  if (std::find(used.begin(), used.end(), c.labels[0]) != used.end())
    throw InputError(db.path(), 0, "the live loop's models already use " + c.labels[0]);
  Transaction tx(db);
  auto seen = db.prepare("SELECT 1 FROM talc_input_requests WHERE input = ?");
  seen.bind(1, name);
  if (seen.step()) throw InputError(db.path(), 0, name + " was requested already (the loop takes it at its next pass)");
  seen.reset();
  db.prepare("INSERT INTO talc_input_requests (input) VALUES (?)").bind(1, name).run();
  tx.commit();
}

bool LiveLoop::started() const { return tc_ != nullptr; }
TalcPhase LiveLoop::phase() const { return tc_ ? tc_->phase() : TalcPhase::calibration; }

void LiveLoop::load() {
  Database& db = store_.database();
  if (inputs_.names.empty()) {
    auto h = db.prepare("SELECT header FROM input_source WHERE id = 1");
    if (h.step()) {
      const std::vector<std::string> names = csvHeaderFields(h.text(0) + "\n");
      if (!names.empty()) {
        inputs_.file = db.path() + " (inputs)";
        inputs_.names = names;
        inputs_.columns.assign(names.size(), {});
        columns_ = std::make_unique<model::TalcInputColumns>(model::resolveTalcInputs(inputs_, o_.talc.inputs));
      }
    }
  }
  if (!inputs_.names.empty()) {
    auto h = db.prepare("SELECT header FROM input_source WHERE id = 1");
    h.step();
    std::string header = h.text(0);
    header = header.substr(header.find_last_of('\n') == std::string::npos ? 0 : header.find_last_of('\n') + 1);
    auto q = db.prepare("SELECT text FROM input_samples WHERE time_s > ? ORDER BY time_s");
    q.bind(1, inputs_.t_s.empty() ? -1e300 : inputs_.t_s.back());
    std::string text = header + "\n";
    int n = 0;
    while (q.step()) {
      text += q.text(0) + "\n";
      ++n;
    }
    if (n > 0) {
      const CsvTable t = parseCsv(text, inputs_.file);
      for (const auto& row : t.rows) {
        inputs_.t_s.push_back(t.number(row, 0));
        for (std::size_t c = 0; c < inputs_.names.size(); ++c)
          inputs_.columns[c].push_back(t.number(row, static_cast<int>(c)));
      }
    }
  }
  auto q = db.prepare("SELECT cycle, time_s FROM cycles WHERE status IN ('reference', 'evaluated') AND cycle > ? "
                      "ORDER BY cycle");
  q.bind(1, last_loaded_cycle_);
  auto v = db.prepare("SELECT value FROM errors WHERE cycle = ? AND channel = ?");
  auto span = db.prepare("SELECT MIN(time_s), MAX(time_s) FROM log_points WHERE cycle = ?");
  while (q.step()) {
    Measurement m;
    m.cycle = static_cast<int>(q.integer(0));
    m.t_s = q.real(1);
    for (const auto& c : channels_) {
      v.bind(1, m.cycle).bind(2, c);
      if (!v.step()) throw InputError(db.path(), 0, "cycle " + std::to_string(m.cycle) + " has no " + c);
      m.values.push_back(v.real(0));
      v.reset();
    }
    span.bind(1, m.cycle);
    span.step();
    m.first_point_s = span.isNull(0) ? m.t_s : span.real(0);
    m.last_point_s = span.isNull(1) ? m.t_s : span.real(1);
    span.reset();
    meas_.push_back(std::move(m));
    last_loaded_cycle_ = meas_.back().cycle;
  }
}

std::optional<double> LiveLoop::openCycleFirstPoint(bool& untimed) const {
  auto q = store_.database().prepare(
      "SELECT MIN(time_s), SUM(time_s IS NULL), COUNT(*) FROM log_points WHERE cycle NOT IN (SELECT cycle FROM cycles)");
  q.step();
  untimed = q.integer(2) > 0 && q.integer(1) > 0;
  if (q.integer(2) == 0 || q.isNull(0)) return std::nullopt;
  return q.real(0);
}

// The first input sample at or after tk (tk itself when the rows are held at the end).
static double firstSampleAtOrAfter(const std::vector<double>& t, double tk) {
  const auto it = std::lower_bound(t.begin(), t.end(), tk);
  return it == t.end() ? tk : *it;
}

double LiveLoop::issuedTime(double tk) const {
  const double s = firstSampleAtOrAfter(inputs_.t_s, tk);
  double issued = s;
  for (auto it = meas_.rbegin(); it != meas_.rend(); ++it) {
    if (it->last_point_s < s - 86400.0) break;
    if (it->first_point_s <= s && s < it->last_point_s) issued = std::max(issued, it->last_point_s);
  }
  return issued;
}

bool LiveLoop::run(bool finished, bool write, LiveProgress* progress, bool log_pending) {
  load();
  if (!tc_) {
    if (meas_.empty() || !columns_) return false;
    t0_ = meas_.front().t_s;  // the reference cycle
    tc_ = std::make_unique<model::TalcController>(o_.talc, channels_, columns_->labels, grid_s_, t0_);
  }
  for (;;) {
    applyInputChanges(write);
    const Measurement* m = next_meas_ < meas_.size() ? &meas_[next_meas_] : nullptr;
    if (m && !write && !std::binary_search(stored_cycles_.begin(), stored_cycles_.end(), m->cycle)) m = nullptr;
    if (m && tc_->gridIndex(m->t_s) < next_tick_) {
      std::optional<Transaction> tx;  // one step, one transaction
      if (write) tx.emplace(store_.database());
      maybeCloseCalibration(m->t_s, false, write);
      processMeasurement(*m, write);
      if (tx) tx->commit();
      ++next_meas_;
      if (progress) progress->measurements++;
      continue;
    }
    const int k = next_tick_;
    const double tk = tc_->gridTime(k);
    if (!write) {
      if (k >= stored_ticks_) break;
    } else {
      const bool covered = !inputs_.t_s.empty() && inputs_.t_s.back() >= tk;
      if (!covered && !(finished && m)) break;
      if (!finished) {
        const double s = firstSampleAtOrAfter(inputs_.t_s, tk);
        bool untimed = false;
        const auto first = openCycleFirstPoint(untimed);
        if (untimed || (first && *first < s)) break;
        if (log_pending) {
          // The torn line is at or after the last complete one: it cannot start a cycle before that.
          auto q = store_.database().prepare("SELECT MAX(time_s), SUM(time_s IS NULL) FROM log_points");
          q.step();
          if (q.isNull(0) || q.integer(1) > 0 || s > q.real(0)) break;
        }
      }
    }
    std::optional<Transaction> tx;
    if (write) tx.emplace(store_.database());
    maybeCloseCalibration(tk, true, write);
    processTick(k, finished, write);
    if (tx) tx->commit();
    ++next_tick_;
    if (progress) progress->ticks++;
  }
  applyInputChanges(write);
  return true;
}

// Stored changes at their step count (a rebuild); in a writing run, then the requests not yet
// applied, here and now (recorded with the step count, in a transaction of their own).
void LiveLoop::applyInputChanges(bool write) {
  const int steps = next_tick_ + static_cast<int>(next_meas_);
  while (changes_applied_ < changes_.size() && changes_[changes_applied_].after_steps == steps)
    addInput(changes_[changes_applied_++].input);
  if (!write || changes_applied_ < changes_.size()) return;
  Database& db = store_.database();
  std::vector<std::string> requested;
  {
    auto q = db.prepare("SELECT input FROM talc_input_requests WHERE input NOT IN (SELECT input FROM talc_input_changes) "
                        "ORDER BY seq");
    while (q.step()) requested.push_back(q.text(0));
  }
  for (const auto& name : requested) {
    Transaction tx(db);
    addInput(name);
    const double t = tc_->inputRows() > 0 ? tc_->gridTime(tc_->inputRows() - 1) : t0_;
    db.prepare("INSERT INTO talc_input_changes (input, label, after_steps, t_s) VALUES (?, ?, ?, ?)")
        .bind(1, name).bind(2, columns_->labels.back()).bind(3, steps).bind(4, t).run();
    recordNew(true, t);
    tx.commit();
    changes_.push_back({name, steps});
    ++changes_applied_;
  }
}

void LiveLoop::addInput(const std::string& name) {
  const model::TalcInputColumns add = model::resolveTalcInputs(inputs_, {name});
  for (const auto& l : columns_->labels)
    if (l == add.labels[0]) return;  // already in the model: nothing to add
  std::vector<double> values;
  for (int k = 0; k < tc_->inputRows(); ++k) values.push_back(model::talcInputRow(add, inputs_, tc_->gridTime(k), t0_)[0]);
  columns_->labels.push_back(add.labels[0]);
  columns_->column.push_back(add.column[0]);
  columns_->absolute.push_back(add.absolute[0]);
  columns_->relative.push_back(add.relative[0]);
  tc_->addInput(add.labels[0], values, o_.talc.nb);
}

// Which input the models miss: every column they do not use, scored on the latest update's
// data (the MDL criterion per channel without and with it); the one that lowers it by 20 % or
// more on the most channels (then by the mean gain) is named with its command.
std::string LiveLoop::diagnose() const {
  const int kend = tc_->lastUpdateIndex();
  if (kend < 0) return "";
  struct Best {
    std::string name, label;
    int helped = 0;
    double mean_gain = 0;
    std::vector<double> gains;
  };
  std::optional<Best> best;
  for (const auto& name : inputs_.names) {
    if (name == "time_s") continue;
    model::TalcInputColumns c;
    try {
      c = model::resolveTalcInputs(inputs_, {name});
    } catch (const InputError&) {
      continue;
    }
    if (std::find(columns_->labels.begin(), columns_->labels.end(), c.labels[0]) != columns_->labels.end()) continue;
    std::vector<double> values;
    for (int k = 0; k <= kend; ++k) values.push_back(model::talcInputRow(c, inputs_, tc_->gridTime(k), t0_)[0]);
    const auto s = tc_->scoreCandidate(values, kend);
    if (!s) continue;
    Best b{name, c.labels[0], 0, 0, {}};
    for (std::size_t q = 0; q < s->mdl_without.size(); ++q) {
      const double g = s->mdl_without[q] > 0 ? 1 - s->mdl_with[q] / s->mdl_without[q] : 0;
      b.gains.push_back(g);
      b.helped += g >= 0.2 ? 1 : 0;
      b.mean_gain += g / static_cast<double>(s->mdl_without.size());
    }
    if (b.helped > 0 && (!best || b.helped > best->helped || (b.helped == best->helped && b.mean_gain > best->mean_gain)))
      best = b;
  }
  if (!best) return "no input the models do not use lowers their MDL criterion by 20 % on any channel";
  std::ostringstream s;
  s << "the models miss " << best->label << ": with it the MDL criterion falls";
  bool first = true;
  for (std::size_t q = 0; q < best->gains.size(); ++q)
    if (best->gains[q] >= 0.2) {
      s << (first ? " " : ", ") << static_cast<int>(std::lround(100 * best->gains[q])) << " % on " << channels_[q];
      first = false;
    }
  s << "; add it: probeloop campaign add-input " << store_.database().path() << " " << best->name;
  return s.str();
}

void LiveLoop::maybeCloseCalibration(double step_t, bool at_tick, bool write) {
  if (tc_->compensating() || last_cp_k_ < 0) return;
  const double D = grid_s_, tol = D / 4;
  std::string why;
  if (o_.talc.cp_h > 0) {
    if (cp_extended_) return;  // closes at a CP measurement
    const double limit = t0_ + o_.talc.cp_h * 3600.0 + tol;
    if (!(at_tick ? step_t > limit + D / 2 : step_t > limit)) return;
    if (!tc_->closeCalibration(last_cp_k_, o_.talc.cp_h * 3600.0, why)) {
      cp_extended_ = true;
      tc_->addEvent({step_t, "", 0, "calibration phase extended: " + why});
    }
  } else if (at_tick) {
    // As short as possible: before grid step k + 1, the CP ending at k (every measurement up
    // to k is in) if both criteria hold and every channel is identified.
    const int k = next_tick_ - 1;
    if (k < 0 || k * D < tc_->cpRequiredS() - 1e-9 * D) return;
    tc_->closeCalibration(k, k * D, why);
  }
  recordNew(write, step_t);
}

void LiveLoop::processTick(int k, bool /*finished*/, bool write) {
  Database& db = store_.database();
  const double tk = tc_->gridTime(k);
  tc_->appendInputRow(model::talcInputRow(*columns_, inputs_, tk, t0_));
  const std::vector<double> pred = tc_->predict(k);
  double issued = 0;
  if (write) {
    issued = issuedTime(tk);
  } else {
    auto q = db.prepare("SELECT applies_s FROM talc_ticks WHERE k = ?");
    q.bind(1, k);
    if (!q.step()) throw InputError(db.path(), 0, "grid step " + std::to_string(k) + " missing from the store");
    issued = q.real(0);
  }
  if (!pred.empty()) {
    Issued is;
    is.k = k;
    is.applies_s = issued;
    for (std::size_t q = 0; q < channels_.size(); ++q) {
      const auto& names = geometry::LocationErrors::names();
      const auto at = std::find(names.begin(), names.end(), channels_[q]) - names.begin();
      is.values[static_cast<std::size_t>(at)] = pred[q];
    }
    issued_.push_back(is);
  }
  if (write) {
    db.prepare("INSERT INTO talc_ticks (k, t_s, issued_s, applies_s, phase, model_version) VALUES (?, ?, ?, ?, ?, ?)")
        .bind(1, k).bind(2, tk).bind(3, issued).bind(4, issued).bind(5, std::string(model::talcPhaseName(tc_->phase())))
        .bind(6, pred.empty() ? std::optional<double>() : std::optional<double>(models_recorded_)).run();
    auto ins = db.prepare("INSERT INTO predictions (k, channel, value) VALUES (?, ?, ?)");
    for (std::size_t q = 0; q < pred.size(); ++q) ins.bind(1, k).bind(2, channels_[q]).bind(3, pred[q]).run();
  }
  recordNew(write, tk);
}

void LiveLoop::processMeasurement(const Measurement& m, bool write) {
  Database& db = store_.database();
  LiveMeasurement lm;
  lm.cycle = m.cycle;
  lm.t_s = m.t_s;
  lm.k = tc_->gridIndex(m.t_s);
  lm.phase_before = model::talcPhaseName(tc_->phase());
  lm.measured = m.values;
  lm.uncompensated = m.values;
  std::optional<int> applied_k;
  if (o_.offsets_applied) {
    // The prediction in effect while the cycle ran (at its time): the cycle measured the residual.
    for (auto it = issued_.rbegin(); it != issued_.rend(); ++it)
      if (it->applies_s <= m.t_s) {
        applied_k = it->k;
        lm.offset_applied = true;
        const auto& names = geometry::LocationErrors::names();
        for (std::size_t q = 0; q < channels_.size(); ++q) {
          const auto at = std::find(names.begin(), names.end(), channels_[q]) - names.begin();
          lm.uncompensated[q] += it->values[static_cast<std::size_t>(at)];
        }
        break;
      }
  }
  if (tc_->compensating()) {
    if (o_.requested_only && !tc_->wants(m.t_s)) {
      lm.taken = false;
      lm.predicted = tc_->predict(lm.k);
      for (std::size_t q = 0; q < channels_.size(); ++q) lm.residual.push_back(lm.uncompensated[q] - lm.predicted[q]);
    } else {
      lm.residual = tc_->measure(m.t_s, lm.uncompensated);
      for (std::size_t q = 0; q < channels_.size(); ++q) lm.predicted.push_back(lm.uncompensated[q] - lm.residual[q]);
    }
  } else {
    tc_->measure(m.t_s, lm.uncompensated);
    last_cp_k_ = lm.k;
    last_cp_t_ = m.t_s;
    std::string why;
    if (cp_extended_ && tc_->closeCalibration(lm.k, lm.k * grid_s_, why)) cp_extended_ = false;
  }
  if (write) {
    db.prepare("INSERT INTO talc_measurements (cycle, k, t_s, phase_before, taken, applied_k) VALUES (?, ?, ?, ?, ?, ?)")
        .bind(1, m.cycle).bind(2, lm.k).bind(3, m.t_s).bind(4, lm.phase_before).bind(5, lm.taken ? 1 : 0)
        .bind(6, applied_k ? std::optional<double>(*applied_k) : std::optional<double>()).run();
    auto ins = db.prepare("INSERT INTO residuals (cycle, channel, measured, uncompensated, predicted, residual) "
                          "VALUES (?, ?, ?, ?, ?, ?)");
    for (std::size_t q = 0; q < channels_.size(); ++q) {
      ins.bind(1, m.cycle).bind(2, channels_[q]).bind(3, lm.measured[q]).bind(4, lm.uncompensated[q]);
      if (lm.predicted.empty()) {
        ins.bindNull(5).bindNull(6);
      } else {
        ins.bind(5, lm.predicted[q]).bind(6, lm.residual[q]);
      }
      ins.run();
    }
  }
  done_measurements_.push_back(std::move(lm));
  recordNew(write, m.t_s);
}

// The controller's new events, model versions and phase change since the last step.
void LiveLoop::recordNew(bool write, double t_s) {
  Database& db = store_.database();
  const auto& ev = tc_->events();
  for (; events_recorded_ < ev.size(); ++events_recorded_) {
    const auto& e = ev[events_recorded_];
    if (write)
      db.prepare("INSERT INTO talc_events (t_s, channel, residual, action) VALUES (?, ?, ?, ?)")
          .bind(1, e.t_s).bind(2, e.channel).bind(3, e.residual).bind(4, e.action).run();
    if (isModelEvent(e.action)) {
      ++models_recorded_;
      if (write) {
        diagnosis_ = diagnose();
        db.prepare("INSERT INTO models (version, t_s, reason, json, diagnosis) VALUES (?, ?, ?, ?, ?)")
            .bind(1, models_recorded_).bind(2, e.t_s).bind(3, e.action).bind(4, modelsJson(*tc_).dump())
            .bind(5, diagnosis_).run();
      } else {
        auto q = db.prepare("SELECT diagnosis FROM models WHERE version = ?");
        q.bind(1, models_recorded_);
        if (q.step()) diagnosis_ = q.text(0);
      }
    }
  }
  const std::string phase = model::talcPhaseName(tc_->phase());
  if (phase != phase_recorded_) {
    if (write) db.prepare("INSERT INTO phases (t_s, phase) VALUES (?, ?)").bind(1, t_s).bind(2, phase).run();
    phase_recorded_ = phase;
  }
}

LiveProgress LiveLoop::advance(bool finished, bool log_pending) {
  LiveProgress p;
  const std::size_t before = tc_ ? tc_->events().size() : 0;
  run(finished, true, &p, log_pending);
  if (tc_)
    for (std::size_t i = before; i < tc_->events().size(); ++i) p.events.push_back(tc_->events()[i]);
  return p;
}

double LiveLoop::waitSeconds(double now_s) const {
  double due = 0;
  if (!tc_) {
    due = meas_.empty() ? now_s : meas_.back().t_s + grid_s_;
  } else if (next_meas_ < meas_.size()) {
    // A cycle is in but not processed yet (its grid step waits for the inputs): what TALC will
    // ask for once it is, on a copy with the inputs held at their latest values.
    model::TalcController copy = *tc_;
    for (std::size_t j = next_meas_; j < meas_.size(); ++j) {
      const int k = copy.gridIndex(meas_[j].t_s);
      for (int i = copy.inputRows(); i <= k; ++i)
        copy.appendInputRow(model::talcInputRow(*columns_, inputs_, copy.gridTime(i), t0_));
      if (copy.compensating()) copy.predict(k);
      copy.measure(meas_[j].t_s, meas_[j].values);
    }
    due = copy.nextDue();
  } else {
    due = tc_->nextDue();
  }
  if (tc_ && !tc_->compensating() && o_.talc.cp_h > 0 && due - t0_ > o_.talc.cp_h * 3600.0 + grid_s_ / 4)
    due = t0_ + o_.talc.cp_h * 3600.0 + o_.talc.post_interval_h * 3600.0;  // the CP is over
  // The cycle's time is the mean of its points' times: about half a cycle after its start.
  return std::max(0.0, due - cycle_time_s_ / 2 - now_s);
}

std::optional<std::array<double, 7>> LiveLoop::compensationAt(double t_s) const {
  for (auto it = issued_.rbegin(); it != issued_.rend(); ++it)
    if (it->applies_s <= t_s) return it->values;
  return std::nullopt;
}

}  // namespace probeloop::campaign
