#include "campaign/store.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/input_file.hpp"
#include "evaluate/ingest.hpp"
#include "evaluate/sphere_campaign.hpp"
#include "geometry/location_errors.hpp"

namespace probeloop::campaign {
namespace {

// 'PLCS': marks the file as a probeloop campaign store (PRAGMA application_id), so that another
// SQLite database given by mistake is named as such.
constexpr int kApplicationId = 0x504C4353;

// Schema version 1 (docs/formats.md#campaign-store). Every table a later version adds comes with
// a migration in open(); a store of a version above kStoreSchemaVersion is refused.
const char* kSchemaV1 = R"sql(
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE manifest (id INTEGER PRIMARY KEY CHECK (id = 1), file TEXT NOT NULL, kind TEXT NOT NULL,
                       json TEXT NOT NULL);
CREATE TABLE log_sources (source_id INTEGER PRIMARY KEY, path TEXT NOT NULL UNIQUE,
                          bytes_read INTEGER NOT NULL, lines_read INTEGER NOT NULL,
                          last_line TEXT NOT NULL, session_start_s REAL);
CREATE TABLE log_points (source_id INTEGER NOT NULL REFERENCES log_sources, line INTEGER NOT NULL,
                         cycle INTEGER NOT NULL, position INTEGER NOT NULL, point INTEGER NOT NULL,
                         x_mm REAL NOT NULL, y_mm REAL NOT NULL, z_mm REAL NOT NULL, time_s REAL,
                         PRIMARY KEY (source_id, line), UNIQUE (cycle, position, point));
CREATE TABLE quarantine (source_id INTEGER NOT NULL REFERENCES log_sources, line INTEGER NOT NULL,
                         text TEXT NOT NULL, reason TEXT NOT NULL, PRIMARY KEY (source_id, line));
CREATE TABLE cycles (cycle INTEGER PRIMARY KEY,
                     status TEXT NOT NULL CHECK (status IN ('reference', 'evaluated', 'incomplete')),
                     time_s REAL, reason TEXT NOT NULL DEFAULT '');
CREATE TABLE errors (cycle INTEGER NOT NULL REFERENCES cycles, channel TEXT NOT NULL, value REAL NOT NULL,
                     U REAL NOT NULL, PRIMARY KEY (cycle, channel));
CREATE TABLE scatter_terms (cycle INTEGER NOT NULL REFERENCES cycles, ordinal INTEGER NOT NULL,
                            position INTEGER NOT NULL, ssr_mm2 REAL NOT NULL, dof REAL NOT NULL,
                            PRIMARY KEY (cycle, ordinal));
CREATE TABLE input_source (id INTEGER PRIMARY KEY CHECK (id = 1), path TEXT NOT NULL, header TEXT NOT NULL,
                           bytes_read INTEGER NOT NULL, lines_read INTEGER NOT NULL, last_line TEXT NOT NULL);
CREATE TABLE input_samples (time_s REAL PRIMARY KEY, line INTEGER NOT NULL, text TEXT NOT NULL);
)sql";

// Schema version 2: the live TALC loop (campaign/live_loop.hpp). A version-1 store gains these
// tables the first time a live loop opens it (upgradeToLiveSchema); every later version adds
// its own migration there.
const char* kSchemaV2 = R"sql(
CREATE TABLE talc_config (id INTEGER PRIMARY KEY CHECK (id = 1), json TEXT NOT NULL);
CREATE TABLE talc_ticks (k INTEGER PRIMARY KEY, t_s REAL NOT NULL, issued_s REAL NOT NULL, applies_s REAL NOT NULL,
                         phase TEXT NOT NULL, model_version INTEGER);
CREATE TABLE predictions (k INTEGER NOT NULL REFERENCES talc_ticks, channel TEXT NOT NULL, value REAL NOT NULL,
                          PRIMARY KEY (k, channel));
CREATE TABLE talc_measurements (cycle INTEGER PRIMARY KEY REFERENCES cycles, k INTEGER NOT NULL, t_s REAL NOT NULL,
                                phase_before TEXT NOT NULL, taken INTEGER NOT NULL, applied_k INTEGER);
CREATE TABLE residuals (cycle INTEGER NOT NULL REFERENCES talc_measurements, channel TEXT NOT NULL,
                        measured REAL NOT NULL, uncompensated REAL NOT NULL, predicted REAL, residual REAL,
                        PRIMARY KEY (cycle, channel));
CREATE TABLE talc_events (seq INTEGER PRIMARY KEY, t_s REAL NOT NULL, channel TEXT NOT NULL, residual REAL,
                          action TEXT NOT NULL);
CREATE TABLE models (version INTEGER PRIMARY KEY, t_s REAL NOT NULL, reason TEXT NOT NULL, json TEXT NOT NULL,
                     diagnosis TEXT NOT NULL DEFAULT '');
CREATE TABLE talc_input_requests (seq INTEGER PRIMARY KEY, input TEXT NOT NULL UNIQUE);
CREATE TABLE talc_input_changes (seq INTEGER PRIMARY KEY, input TEXT NOT NULL UNIQUE, label TEXT NOT NULL,
                                 after_steps INTEGER NOT NULL, t_s REAL NOT NULL);
CREATE TABLE phases (seq INTEGER PRIMARY KEY, t_s REAL NOT NULL, phase TEXT NOT NULL);
)sql";

std::string absolute(const std::string& p) { return std::filesystem::absolute(p).lexically_normal().string(); }

std::string meta(Database& db, const std::string& key) {
  auto q = db.prepare("SELECT value FROM meta WHERE key = ?");
  q.bind(1, key);
  return q.step() ? q.text(0) : std::string();
}

// A followed file: its complete lines since the last ingest (a '\r' before the '\n' removed),
// the last one as it is in the file, and the bytes of a torn last line that wait.
struct Followed {
  std::vector<std::string> lines;
  std::string last_raw;
  std::size_t used = 0, waiting = 0;
};

// Reads from the start of the last ingested line, which must still be there unchanged: a file
// that shrank or was rewritten is refused rather than read from the wrong place.
Followed follow(const std::string& path, std::int64_t bytes_read, const std::string& last_raw) {
  const std::string expect = bytes_read > 0 ? last_raw + "\n" : std::string();
  if (static_cast<std::size_t>(bytes_read) < expect.size())
    throw InputError(path, 0, "the store's record of this file is inconsistent (bytes read " + std::to_string(bytes_read) + ")");
  const FileTail t = readFileTail(path, static_cast<std::size_t>(bytes_read) - expect.size());
  if (t.file_size < static_cast<std::size_t>(bytes_read))
    throw InputError(path, 0, "the file has " + std::to_string(t.file_size) + " bytes, fewer than the " +
                                  std::to_string(bytes_read) + " already ingested: it was replaced or truncated (a new log "
                                  "goes in under its own name)");
  if (t.bytes.compare(0, expect.size(), expect) != 0)
    throw InputError(path, 0, "the part already ingested has changed (its last ingested line is no longer '" + last_raw +
                                  "'): the file was rewritten; a new log goes in under its own name");
  Followed f;
  std::size_t at = expect.size();
  for (std::size_t nl; (nl = t.bytes.find('\n', at)) != std::string::npos; at = nl + 1) {
    f.last_raw = t.bytes.substr(at, nl - at);
    std::string l = f.last_raw;
    if (!l.empty() && l.back() == '\r') l.pop_back();
    f.lines.push_back(std::move(l));
  }
  f.used = at - expect.size();
  f.waiting = t.bytes.size() - at;
  return f;
}

std::vector<evaluate::ProbeRecord> cycleRecords(Database& db, int cycle) {
  auto q = db.prepare(
      "SELECT s.path, p.line, p.position, p.point, p.x_mm, p.y_mm, p.z_mm, p.time_s FROM log_points p "
      "JOIN log_sources s USING (source_id) WHERE p.cycle = ? ORDER BY p.source_id, p.line");
  q.bind(1, cycle);
  std::vector<evaluate::ProbeRecord> out;
  while (q.step()) {
    evaluate::ProbeRecord r;
    r.file = q.text(0);
    r.line = static_cast<int>(q.integer(1));
    r.cycle = cycle;
    r.position = static_cast<int>(q.integer(2));
    r.point = static_cast<int>(q.integer(3));
    r.tip_mm = Eigen::Vector3d(q.real(4), q.real(5), q.real(6));
    if (!q.isNull(7)) r.time_s = q.real(7);
    out.push_back(r);
  }
  return out;
}

void storeCycle(Database& db, int cycle, const std::string& status, std::optional<double> time_s,
                const std::string& reason) {
  db.prepare("INSERT INTO cycles (cycle, status, time_s, reason) VALUES (?, ?, ?, ?)")
      .bind(1, cycle).bind(2, status).bind(3, time_s).bind(4, reason).run();
}

void storeEvaluated(Database& db, const evaluate::CycleEvaluation& c, const std::string& status) {
  storeCycle(db, c.cycle, status, c.time_s, "");
  auto e = db.prepare("INSERT INTO errors (cycle, channel, value, U) VALUES (?, ?, ?, ?)");
  const auto values = c.least_squares.values();
  for (int i = 0; i < geometry::LocationErrors::kCount; ++i)
    e.bind(1, c.cycle).bind(2, std::string(geometry::LocationErrors::names()[i])).bind(3, values[i]).bind(4, c.budgets[i].U).run();
  auto s = db.prepare("INSERT INTO scatter_terms (cycle, ordinal, position, ssr_mm2, dof) VALUES (?, ?, ?, ?, ?)");
  int ordinal = 0;
  for (const auto& t : evaluate::scatterTerms(c))
    s.bind(1, c.cycle).bind(2, ordinal++).bind(3, t.position).bind(4, t.ssr_mm2).bind(5, t.dof).run();
}

// Why a cycle cannot be evaluated from its points (the evaluation's own rule: >= 4 points at
// every position), or "" when it can.
std::string missingPoints(const parts::PlanManifest& m, const std::vector<evaluate::ProbeRecord>& records) {
  std::map<int, int> per;
  for (const auto& r : records) ++per[r.position];
  std::string why;
  for (const auto& s : m.spheres)
    if (per[s.position] < 4)
      why += (why.empty() ? "" : ", ") + std::string("position ") + std::to_string(s.position) + ": " +
             std::to_string(per[s.position]) + " points";
  return why.empty() ? why : why + " (a sphere needs at least 4)";
}

}  // namespace

void CampaignStore::create(const std::string& path, const std::string& manifest_path) {
  const std::string text = readFile(manifest_path, kJsonInput);
  const parts::PlanManifest m = parts::parseManifest(text, manifest_path);
  if (m.pieceKind() != parts::PieceKind::SphereArtifact)
    throw InputError(manifest_path, 0, "a campaign store follows a sphere-artifact campaign (seed 004 Ch. 5-6); this plan is a " +
                                           m.kind);
  // Built under a temporary name and renamed: a crash leaves no half-made store in its place.
  const std::string tmp = path + ".tmp-init";
  std::filesystem::remove(tmp);
  if (std::filesystem::exists(path))
    throw InputError(path, 0, "already exists: a campaign store is created once (remove it first to start over)");
  // A write-ahead log left by a store that was deleted without it belongs to that store:
  // SQLite would replay it into the new one (a "malformed" store at the first open).
  std::filesystem::remove(path + "-wal");
  std::filesystem::remove(path + "-shm");
  {
    Database db(tmp, Database::Mode::Create);
    db.exec("PRAGMA journal_mode = DELETE");
    Transaction t(db);
    db.exec(kSchemaV1);
    db.exec(kSchemaV2);
    db.exec("PRAGMA application_id = " + std::to_string(kApplicationId));
    db.exec("PRAGMA user_version = " + std::to_string(kStoreSchemaVersion));
    db.prepare("INSERT INTO meta (key, value) VALUES ('schema_version', ?)").bind(1, std::to_string(kStoreSchemaVersion)).run();
    db.prepare("INSERT INTO meta (key, value) VALUES ('machine', ?)").bind(1, m.machine_name).run();
    db.prepare("INSERT INTO manifest (id, file, kind, json) VALUES (1, ?, ?, ?)").bind(1, manifest_path).bind(2, m.kind).bind(3, text).run();
    t.commit();
    // WAL from here on: a reader (`campaign status`) never blocks the writer.
    db.exec("PRAGMA journal_mode = WAL");
  }
  std::filesystem::rename(tmp, path);
}

CampaignStore::CampaignStore(const std::string& path) : db_(path, Database::Mode::OpenExisting) {
  {
    auto q = db_.prepare("PRAGMA application_id");
    if (!q.step() || q.integer(0) != kApplicationId)
      throw InputError(path, 0, "not a probeloop campaign store (an SQLite file of another kind, or not SQLite)");
  }
  auto v = db_.prepare("PRAGMA user_version");
  v.step();
  const int version = static_cast<int>(v.integer(0));
  if (version > kStoreSchemaVersion)
    throw InputError(path, 0, "a campaign store of schema version " + std::to_string(version) + ", newer than the " +
                                  std::to_string(kStoreSchemaVersion) + " this probeloop reads: use the probeloop that wrote it "
                                  "(the store is left as it is)");
  // Durability (docs/reliability.md#campaign-store): WAL with synchronous = FULL, so that a
  // committed ingest survives a power loss, not only a crash of this process.
  db_.exec("PRAGMA journal_mode = WAL; PRAGMA synchronous = FULL; PRAGMA foreign_keys = ON");
  auto m = db_.prepare("SELECT file, json FROM manifest WHERE id = 1");
  if (!m.step()) throw InputError(path, 0, "campaign store without its plan manifest");
  manifest_ = parts::parseManifest(m.text(1), path + " (manifest " + m.text(0) + ")");
}

void CampaignStore::upgradeToLiveSchema() {
  auto v = db_.prepare("PRAGMA user_version");
  v.step();
  if (v.integer(0) >= 2) return;
  Transaction tx(db_);
  db_.exec(kSchemaV2);
  db_.exec("PRAGMA user_version = 2");
  db_.exec("UPDATE meta SET value = '2' WHERE key = 'schema_version'");
  tx.commit();
}

IngestReport CampaignStore::ingestLog(const std::string& log_path, bool finished) {
  IngestReport rep;
  const std::string key = absolute(log_path);
  Transaction tx(db_);
  std::int64_t source_id = 0, bytes_read = 0, lines_read = 0;
  std::string last_line;
  std::optional<double> session_start;
  {
    auto q = db_.prepare("SELECT source_id, bytes_read, lines_read, last_line, session_start_s FROM log_sources WHERE path = ?");
    q.bind(1, key);
    if (q.step()) {
      source_id = q.integer(0);
      bytes_read = q.integer(1);
      lines_read = q.integer(2);
      last_line = q.text(3);
      if (!q.isNull(4)) session_start = q.real(4);
    } else {
      db_.prepare("INSERT INTO log_sources (path, bytes_read, lines_read, last_line) VALUES (?, 0, 0, '')").bind(1, key).run();
      auto id = db_.prepare("SELECT last_insert_rowid()");
      id.step();
      source_id = id.integer(0);
    }
  }
  const Followed f = follow(log_path, bytes_read, last_line);
  rep.lines = static_cast<int>(f.lines.size());
  rep.waiting_bytes = static_cast<int>(f.waiting);

  // Each line on its own: a line that is no log line is quarantined, not fatal.
  std::vector<evaluate::ProbeRecord> fresh;
  auto quarantine = db_.prepare("INSERT INTO quarantine (source_id, line, text, reason) VALUES (?, ?, ?, ?)");
  for (std::size_t i = 0; i < f.lines.size(); ++i) {
    const int line = static_cast<int>(lines_read + 1 + static_cast<std::int64_t>(i));
    std::optional<double> start = session_start;
    try {
      const auto r = evaluate::probeLogRecords(f.lines[i] + "\n", log_path, line, &start);
      session_start = start;
      fresh.insert(fresh.end(), r.begin(), r.end());
    } catch (const InputError& e) {
      quarantine.bind(1, source_id).bind(2, line).bind(3, f.lines[i]).bind(4, std::string(e.what())).run();
      ++rep.quarantined;
    }
  }
  // Points that cannot belong to the plan refuse the whole ingest (another plan's log).
  evaluate::checkRecordsBelongToPlan(fresh, manifest_, log_path);
  auto seen = db_.prepare("SELECT s.path, p.line FROM log_points p JOIN log_sources s USING (source_id) "
                          "WHERE p.cycle = ? AND p.position = ? AND p.point = ?");
  auto insert = db_.prepare("INSERT INTO log_points (source_id, line, cycle, position, point, x_mm, y_mm, z_mm, time_s) "
                            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)");
  std::map<int, bool> touched;
  for (const auto& r : fresh) {
    seen.bind(1, r.cycle).bind(2, r.position).bind(3, r.point);
    if (seen.step()) {
      const std::string where = seen.text(0) + ":" + std::to_string(seen.integer(1));
      seen.reset();
      throw InputError(log_path, r.line, "cycle " + std::to_string(r.cycle) + " position " + std::to_string(r.position) +
                                             " point " + std::to_string(r.point) + " is already in the store (" + where + ")");
    }
    seen.reset();
    insert.bind(1, source_id).bind(2, r.line).bind(3, r.cycle).bind(4, r.position).bind(5, r.point)
        .bind(6, r.tip_mm.x()).bind(7, r.tip_mm.y()).bind(8, r.tip_mm.z()).bind(9, r.time_s).run();
    ++rep.points;
  }
  if (!f.lines.empty()) {
    db_.prepare("UPDATE log_sources SET bytes_read = ?, lines_read = ?, last_line = ?, session_start_s = ? WHERE source_id = ?")
        .bind(1, bytes_read + static_cast<std::int64_t>(f.used))
        .bind(2, lines_read + static_cast<std::int64_t>(f.lines.size()))
        .bind(3, f.last_raw).bind(4, session_start).bind(5, source_id).run();
  }

  // Which cycles are final now, and not yet evaluated.
  const int per_cycle = static_cast<int>(manifest_.spheres.size()) * manifest_.pointsPerSphere();
  std::map<int, int> counts;
  {
    auto q = db_.prepare("SELECT cycle, COUNT(*) FROM log_points WHERE cycle NOT IN (SELECT cycle FROM cycles) GROUP BY cycle");
    while (q.step()) counts[static_cast<int>(q.integer(0))] = static_cast<int>(q.integer(1));
  }
  int last_logged = 0;
  {
    auto q = db_.prepare("SELECT MAX(cycle) FROM log_points");
    if (q.step() && !q.isNull(0)) last_logged = static_cast<int>(q.integer(0));
  }
  int reference = 0;
  {
    auto q = db_.prepare("SELECT cycle FROM cycles WHERE status = 'reference'");
    if (q.step()) reference = static_cast<int>(q.integer(0));
  }
  // Cycles skipped entirely (no point logged while a later cycle has some) are final too.
  {
    auto q = db_.prepare("SELECT COALESCE(MAX(cycle), 0) FROM cycles");
    q.step();
    for (int c = static_cast<int>(q.integer(0)) + 1; c < last_logged; ++c) counts.try_emplace(c, 0);
  }
  for (const auto& [cycle, n] : counts) {
    const bool final = n >= per_cycle || cycle < last_logged || finished;
    if (!final) continue;
    const auto records = cycleRecords(db_, cycle);
    if (records.empty()) {
      storeCycle(db_, cycle, "incomplete", std::nullopt, "no point logged (a later cycle has points)");
      rep.incomplete.push_back(cycle);
      continue;
    }
    const std::string missing = missingPoints(manifest_, records);
    if (!missing.empty()) {
      storeCycle(db_, cycle, "incomplete", std::nullopt, missing);
      rep.incomplete.push_back(cycle);
      continue;
    }
    // What the offline evaluation of the log cut after this cycle uses besides the cycle itself:
    // the reference; the first cycle after it and the one before this (the error rates of the
    // budget's drift term are differences with the neighbouring cycles); the point scatter of
    // every other evaluated cycle (their stored terms).
    evaluate::EvaluateOptions opt;
    std::vector<evaluate::ProbeRecord> all;
    if (reference != 0) {
      std::set<int> with{reference};
      auto n = db_.prepare("SELECT MIN(cycle), MAX(cycle) FROM cycles WHERE status = 'evaluated'");
      if (n.step() && !n.isNull(0)) {
        with.insert(static_cast<int>(n.integer(0)));
        with.insert(static_cast<int>(n.integer(1)));
      }
      for (int c : with) {
        const auto r = cycleRecords(db_, c);
        all.insert(all.end(), r.begin(), r.end());
      }
      auto q = db_.prepare("SELECT cycle, position, ssr_mm2, dof FROM scatter_terms ORDER BY cycle, ordinal");
      while (q.step())
        if (!with.count(static_cast<int>(q.integer(0))))
          opt.prior_scatter.push_back({static_cast<int>(q.integer(0)), static_cast<int>(q.integer(1)), q.real(2), q.real(3)});
    }
    all.insert(all.end(), records.begin(), records.end());
    try {
      const auto e = evaluate::evaluateSphereCampaign(manifest_, all, opt);
      const auto it = std::find_if(e.cycles.begin(), e.cycles.end(), [&](const auto& c) { return c.cycle == cycle; });
      if (it == e.cycles.end()) throw InputError(log_path, 0, "cycle " + std::to_string(cycle) + " was not evaluated");
      storeEvaluated(db_, *it, reference == 0 ? "reference" : "evaluated");
      if (reference == 0) {
        reference = cycle;
        std::string positions;
        for (int p : e.ls_positions) positions += (positions.empty() ? "" : " ") + std::to_string(p);
        db_.prepare("INSERT INTO meta (key, value) VALUES ('least_squares_positions', ?)").bind(1, positions).run();
      }
      rep.evaluated.push_back(cycle);
    } catch (const InputError& e) {
      // A degenerate fit (points of one cycle that do not outline a sphere) stops that cycle,
      // not the campaign.
      storeCycle(db_, cycle, "incomplete", std::nullopt, e.what());
      rep.incomplete.push_back(cycle);
    }
  }
  tx.commit();
  return rep;
}

int CampaignStore::ingestInputs(const std::string& inputs_path) {
  const std::string key = absolute(inputs_path);
  Transaction tx(db_);
  std::int64_t bytes_read = 0, lines_read = 0;
  std::string header, last_line;
  {
    auto q = db_.prepare("SELECT path, header, bytes_read, lines_read, last_line FROM input_source WHERE id = 1");
    if (q.step()) {
      if (q.text(0) != key)
        throw InputError(inputs_path, 0, "this store follows the inputs of " + q.text(0) +
                                             "; one input stream per campaign (concatenate the logger's files in time order)");
      header = q.text(1);
      bytes_read = q.integer(2);
      lines_read = q.integer(3);
      last_line = q.text(4);
    }
  }
  const Followed f = follow(inputs_path, bytes_read, last_line);
  double last_time = -std::numeric_limits<double>::infinity();
  {
    auto q = db_.prepare("SELECT MAX(time_s) FROM input_samples");
    if (q.step() && !q.isNull(0)) last_time = q.real(0);
  }
  auto insert = db_.prepare("INSERT INTO input_samples (time_s, line, text) VALUES (?, ?, ?)");
  // The header line is the last line of `header` (comment lines before it are kept with it, so
  // that the export is the file as written).
  auto headerLine = [&] { return header.substr(header.find_last_of('\n') == std::string::npos ? 0 : header.find_last_of('\n') + 1); };
  bool have_header = false;
  if (!header.empty()) {
    const std::string h = headerLine();
    const std::size_t p = h.find_first_not_of(" \t");
    have_header = p != std::string::npos && h[p] != '#';  // else only the comments before it came yet
  }
  CsvTable head;
  if (have_header) head = parseCsv(headerLine() + "\n", inputs_path);
  int added = 0;
  for (std::size_t i = 0; i < f.lines.size(); ++i) {
    const int line = static_cast<int>(lines_read + 1 + static_cast<std::int64_t>(i));
    const std::string& text = f.lines[i];
    const std::size_t p = text.find_first_not_of(" \t");
    if (!have_header) {
      header += (header.empty() ? "" : "\n") + text;
      if (p == std::string::npos || text[p] == '#') continue;
      if (csvHeaderFields(text).empty() || csvHeaderFields(text).front() != "time_s")
        throw InputError(inputs_path, line, "the inputs' header must start with time_s (found '" + text + "')");
      head = parseCsv(text + "\n", inputs_path);
      have_header = true;
      continue;
    }
    if (p == std::string::npos || text[p] == '#') continue;
    // The row split and read by the CSV rules every reader uses (separator, decimal mark).
    CsvRow row;
    row.line = line;
    for (std::size_t at = 0;;) {
      const std::size_t sep = text.find(head.separator, at);
      std::string field = text.substr(at, sep == std::string::npos ? std::string::npos : sep - at);
      const std::size_t a = field.find_first_not_of(" \t"), b = field.find_last_not_of(" \t");
      row.fields.push_back(a == std::string::npos ? std::string() : field.substr(a, b - a + 1));
      if (sep == std::string::npos) break;
      at = sep + 1;
    }
    if (row.fields.size() != head.header.size())
      throw InputError(inputs_path, line, std::to_string(row.fields.size()) + " fields, the header has " +
                                              std::to_string(head.header.size()));
    double v = 0;
    for (std::size_t c = 0; c < row.fields.size(); ++c)
      if (!head.tryNumber(row, static_cast<int>(c), v))
        throw InputError(inputs_path, line, head.header[c] + ": '" + row.fields[c] + "' is not a finite number");
    const double time = head.number(row, 0);
    if (!(time > last_time))
      throw InputError(inputs_path, line, "time_s " + formatNumber(time) + " does not follow the previous sample's " +
                                              formatNumber(last_time) + ": the logger's clock went backwards or repeated");
    last_time = time;
    insert.bind(1, time).bind(2, line).bind(3, text).run();
    ++added;
  }
  if (!f.lines.empty()) {
    db_.prepare("INSERT INTO input_source (id, path, header, bytes_read, lines_read, last_line) VALUES (1, ?, ?, ?, ?, ?) "
                "ON CONFLICT (id) DO UPDATE SET header = excluded.header, bytes_read = excluded.bytes_read, "
                "lines_read = excluded.lines_read, last_line = excluded.last_line")
        .bind(1, key).bind(2, header).bind(3, bytes_read + static_cast<std::int64_t>(f.used))
        .bind(4, lines_read + static_cast<std::int64_t>(f.lines.size())).bind(5, f.last_raw).run();
  }
  tx.commit();
  return added;
}

StoreStatus CampaignStore::status() {
  StoreStatus s;
  s.path = db_.path();
  s.schema_version = std::stoi(meta(db_, "schema_version"));
  s.machine = meta(db_, "machine");
  s.manifest_file = manifest_.file;
  s.planned_cycles = manifest_.cycles;
  auto count = [&](const char* sql) {
    auto q = db_.prepare(sql);
    q.step();
    return static_cast<int>(q.integer(0));
  };
  s.points = count("SELECT COUNT(*) FROM log_points");
  s.quarantined = count("SELECT COUNT(*) FROM quarantine");
  s.input_samples = count("SELECT COUNT(*) FROM input_samples");
  {
    auto q = db_.prepare("SELECT MAX(time_s) FROM input_samples");
    if (q.step() && !q.isNull(0)) s.inputs_last_time_s = q.real(0);
  }
  auto q = db_.prepare("SELECT cycle, status, time_s, reason FROM cycles ORDER BY cycle");
  auto e = db_.prepare("SELECT value, U FROM errors WHERE cycle = ? AND channel = ?");
  while (q.step()) {
    CycleStatus c;
    c.cycle = static_cast<int>(q.integer(0));
    c.status = q.text(1);
    c.time_s = q.isNull(2) ? 0 : q.real(2);
    c.reason = q.text(3);
    if (c.status == "reference") s.reference_cycle = c.cycle;
    if (c.status != "incomplete")
      for (const char* name : geometry::LocationErrors::names()) {
        e.bind(1, c.cycle).bind(2, std::string(name));
        if (!e.step()) throw InputError(s.path, 0, "cycle " + std::to_string(c.cycle) + " has no " + name + " in the store");
        c.values.push_back(e.real(0));
        c.U.push_back(e.real(1));
        e.reset();
      }
    s.cycles.push_back(std::move(c));
  }
  auto z = db_.prepare("SELECT reason FROM quarantine ORDER BY source_id, line");
  while (z.step()) s.quarantine.push_back(z.text(0));  // "file:line: why", as the reader said it
  return s;
}

std::string CampaignStore::exportErrorsCsv() {
  const StoreStatus s = status();
  evaluate::CampaignEvaluation e;
  e.reference_cycle = s.reference_cycle;
  std::istringstream positions(meta(db_, "least_squares_positions"));
  for (int p; positions >> p;) e.ls_positions.push_back(p);
  for (const auto& c : s.cycles) {
    if (c.status == "incomplete") continue;
    evaluate::CycleEvaluation ce;
    ce.cycle = c.cycle;
    ce.time_s = c.time_s;
    std::array<double, geometry::LocationErrors::kCount> v{};
    for (int i = 0; i < geometry::LocationErrors::kCount; ++i) {
      v[i] = c.values[i];
      ce.budgets[i].U = c.U[i];
    }
    ce.least_squares = geometry::LocationErrors::fromValues(v);
    e.cycles.push_back(std::move(ce));
  }
  if (e.cycles.empty()) return "";
  return evaluate::errorSeriesCsv(e);
}

std::string CampaignStore::exportInputsCsv() {
  auto h = db_.prepare("SELECT header FROM input_source WHERE id = 1");
  if (!h.step()) return "";
  std::string out = h.text(0) + "\n";
  auto q = db_.prepare("SELECT text FROM input_samples ORDER BY time_s");
  while (q.step()) out += q.text(0) + "\n";
  return out;
}

}  // namespace probeloop::campaign
