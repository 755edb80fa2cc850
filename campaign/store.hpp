// The campaign store: one SQLite database per campaign (per machine), holding the plan manifest,
// every ingested controller-log line and input sample, and every cycle's evaluated errors with
// U, so that a campaign is followed while the machine runs instead of evaluated once at the end.
// Schema, versions and durability: docs/formats.md#campaign-store, docs/reliability.md#campaign-store.
//
// Contract:
// - create() writes a new store from a sphere-artifact plan manifest (other kinds: InputError);
//   open() refuses a file that is not a store, or a store of a newer schema version, untouched.
// - ingestLog() reads what a probe log (LinuxCNC LOG / Fanuc DPRNT) gained since the last ingest
//   of the same file, up to its last complete line: a torn last line waits for its end. A line
//   that is not a log line is quarantined with its line number and the ingest goes on; a point
//   that cannot belong to the plan (another plan's log, a point logged twice) refuses the whole
//   ingest. A log that shrank or whose ingested part changed is refused (it was replaced).
// - A cycle is final when all its planned points are in, when a later cycle has points, or when
//   the ingest is told the log is finished (`finished`). Each final cycle is evaluated exactly
//   once, in cycle order: the first complete one is the reference; a later one is evaluated with
//   what the offline evaluation of the log cut after it uses (the reference, the first cycle
//   after it and the previous one: the budget's drift rates are differences with neighbouring
//   cycles; the pooled point scatter of every cycle before it), so that its errors.csv row is
//   the one `probeloop evaluate` gives on the log cut after that cycle, bit for bit. (Offline
//   on the whole log, a cycle's drift rate is a central difference with the next cycle too,
//   and the scatter pools later cycles: the values agree, U may differ in its last digits.) A
//   cycle with a position under 4 points, or whose fit fails, is kept as incomplete with why.
// - ingestInputs() appends an input stream's new rows (time_s first, the header fixed at the
//   first ingest); a time that does not increase, a changed header or a non-finite value is an
//   InputError with file:line.
// - Every ingest is one transaction: on any error the store is exactly as before.
// - exportErrorsCsv() / exportInputsCsv() give today's errors.csv and inputs.csv, which every
//   `model` and `report` command reads; empty when there is nothing of the kind yet. The
//   inputs come back as written: the header with the comment lines before it, then every row
//   (comment and blank lines between rows are not kept).
#pragma once
#include <string>
#include <vector>

#include "campaign/sqlite.hpp"
#include "parts/plan_manifest.hpp"

namespace probeloop::campaign {

constexpr int kStoreSchemaVersion = 2;  // 1: no live-loop tables (upgraded by the live loop)

struct IngestReport {
  int lines = 0;              // complete lines read
  int points = 0;             // probe points stored
  int quarantined = 0;        // lines kept aside
  int waiting_bytes = 0;      // a torn last line, left for the next ingest
  std::vector<int> evaluated; // cycles evaluated by this ingest
  std::vector<int> incomplete;
};

struct CycleStatus {
  int cycle = 0;
  std::string status;  // reference | evaluated | incomplete
  double time_s = 0;
  std::string reason;
  std::vector<double> values, U;  // LocationErrors order; empty when incomplete
};

struct StoreStatus {
  std::string path, manifest_file, machine;
  int schema_version = 0;
  int planned_cycles = 0, points = 0, quarantined = 0, input_samples = 0;
  int reference_cycle = 0;
  std::vector<CycleStatus> cycles;
  std::vector<std::string> quarantine;  // "file:line: reason"
  double inputs_last_time_s = 0;
};

class CampaignStore {
 public:
  static void create(const std::string& path, const std::string& manifest_path);
  explicit CampaignStore(const std::string& path);  // open()

  IngestReport ingestLog(const std::string& log_path, bool finished);
  int ingestInputs(const std::string& inputs_path);  // rows added
  StoreStatus status();
  std::string exportErrorsCsv();
  std::string exportInputsCsv();

  // The live loop's tables (schema 2) on a store created as version 1; nothing if present.
  void upgradeToLiveSchema();
  Database& database() { return db_; }
  const parts::PlanManifest& manifest() const { return manifest_; }

 private:
  Database db_;
  parts::PlanManifest manifest_;
};

}  // namespace probeloop::campaign
