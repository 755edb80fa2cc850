// The campaign store against the offline evaluation: a log ingested in pieces (cut anywhere,
// torn lines included) gives, cycle by cycle, the errors.csv row that `evaluate` gives on the
// log cut after that cycle; every refusal leaves the store as it was.
#include "campaign/store.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "core/error.hpp"
#include "evaluate/ingest.hpp"
#include "evaluate/sphere_campaign.hpp"
#include "parts/machine.hpp"
#include "parts/sphere_artifact.hpp"
#include "planner/sphere_cycle.hpp"

namespace probeloop::campaign {
namespace {

namespace fs = std::filesystem;

struct Fixture : ::testing::Test {
  fs::path dir;
  parts::PlanManifest manifest;
  std::string manifest_path, store_path, log_path;

  void SetUp() override {
    dir = fs::temp_directory_path() / ("probeloop_store_test_" + std::to_string(::getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string src = PROBELOOP_SOURCE_DIR;
    auto artifact = parts::loadSphereArtifact(src + "/parts/sphere_artifact.yaml");
    artifact.cycle_count = 5;
    artifact.duration_s = 0;
    const auto machine = parts::loadMachine(src + "/parts/machines/linuxcnc_rotary_mill.yaml");
    manifest = planner::planSphereCycle(artifact, machine).manifest;
    manifest_path = (dir / "plan.json").string();
    write(manifest_path, parts::manifestToJson(manifest));
    manifest.file = manifest_path;
    store_path = (dir / "m1.campaign").string();
    log_path = (dir / "sphere_probe.log").string();
  }
  void TearDown() override { fs::remove_all(dir); }

  static void write(const std::string& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
  }
  static void append(const std::string& path, const std::string& text) {
    std::ofstream(path, std::ios::binary | std::ios::app) << text;
  }

  // The LinuxCNC LOG of `cycles` cycles: each position's points at their planned contacts, the
  // sphere moved by a drift that grows with the cycle, plus a deterministic scatter of a few
  // tenths of a micrometre (so that the free-radius fits have residuals to pool).
  std::string logText(int cycles, double offset_mm = 0, int skip_cycle = 0, int skip_position = 0) const {
    std::ostringstream o;
    std::uint32_t state = 12345;
    auto noise = [&] {
      state = state * 1664525u + 1013904223u;
      return (static_cast<double>(state >> 8) / 16777216.0 - 0.5) * 6e-4;
    };
    const int per = manifest.pointsPerSphere();
    o.setf(std::ios::fixed);
    o.precision(6);
    for (int c = 1; c <= cycles; ++c)
      for (const auto& s : manifest.spheres) {
        const Eigen::Vector3d drift(0.002 * (c - 1) + offset_mm, -0.001 * (c - 1) * s.position, 0.0005 * (c - 1));
        for (int k = 1; k <= per; ++k) {
          if (c == skip_cycle && s.position == skip_position && k > 2) continue;
          const auto& p = manifest.points[(s.position - 1) * per + (k - 1)];
          const Eigen::Vector3d tip = p.contact_mm + drift + p.approach * noise();
          o << "PT " << c << " " << s.position << " " << k << " " << tip.x() << " " << tip.y() << " " << tip.z() << "\n";
        }
      }
    return o.str();
  }

  // `evaluate`'s errors.csv of a log's text.
  std::string offlineCsv(const std::string& text) const {
    const std::string cut = (dir / "cut.log").string();
    write(cut, text);
    const auto records = evaluate::readProbeRecords(cut, evaluate::PointsFormat::LinuxCncLog, manifest);
    return evaluate::errorSeriesCsv(evaluate::evaluateSphereCampaign(manifest, records));
  }

  static std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
  }

  static std::string bytesOf(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
  }
};

TEST_F(Fixture, LogIngestedInPiecesGivesOfflineRowsCycleByCycle) {
  CampaignStore::create(store_path, manifest_path);
  CampaignStore store(store_path);
  const std::string text = logText(5);
  // Cut at arbitrary bytes (mid-line, mid-number), as a controller flushes its log.
  std::vector<std::size_t> cuts{37, 1000, 1001, 2500, text.size() / 2, text.size() - 5, text.size()};
  std::size_t done = 0;
  int evaluated = 0, waiting_seen = 0;
  for (std::size_t cut : cuts) {
    append(log_path, text.substr(done, cut - done));
    done = cut;
    const auto r = store.ingestLog(log_path, false);
    evaluated += static_cast<int>(r.evaluated.size());
    if (r.waiting_bytes > 0) ++waiting_seen;
  }
  EXPECT_GT(waiting_seen, 0);
  EXPECT_EQ(evaluated, 5);  // the last cycle is complete by count: final without --finished
  const auto exported = lines(store.exportErrorsCsv());
  const auto all = lines(text);
  const int per_cycle = static_cast<int>(manifest.spheres.size()) * manifest.pointsPerSphere();
  for (int c = 1; c <= 5; ++c) {
    std::string cut;
    for (int i = 0; i < c * per_cycle; ++i) cut += all[i] + "\n";
    const auto offline = lines(offlineCsv(cut));
    ASSERT_EQ(offline.size(), static_cast<std::size_t>(2 + c));
    EXPECT_EQ(exported[0], offline[0]);
    EXPECT_EQ(exported[1], offline[1]);
    EXPECT_EQ(exported[1 + c], offline[1 + c]) << "cycle " << c;
  }
  // The whole log at once: the last row (and every value) as offline.
  const auto offline = lines(offlineCsv(text));
  EXPECT_EQ(exported.back(), offline.back());
  // Nothing new: nothing read, nothing evaluated twice.
  const auto again = store.ingestLog(log_path, true);
  EXPECT_EQ(again.lines, 0);
  EXPECT_TRUE(again.evaluated.empty());
  EXPECT_EQ(store.status().cycles.size(), 5u);
}

TEST_F(Fixture, CorruptLineIsQuarantinedAndTheCampaignGoesOn) {
  CampaignStore::create(store_path, manifest_path);
  CampaignStore store(store_path);
  auto all = lines(logText(3));
  all.insert(all.begin() + 7, "PT 1 2 ### garbled by the serial line");
  std::string text;
  for (const auto& l : all) text += l + "\n";
  write(log_path, text);
  const auto r = store.ingestLog(log_path, true);
  EXPECT_EQ(r.quarantined, 1);
  EXPECT_EQ(r.evaluated.size(), 3u);
  const auto s = store.status();
  ASSERT_EQ(s.quarantine.size(), 1u);
  EXPECT_NE(s.quarantine[0].find(":8:"), std::string::npos) << s.quarantine[0];
}

TEST_F(Fixture, CycleWithMissingPointsIsKeptIncompleteAndLaterCyclesEvaluated) {
  CampaignStore::create(store_path, manifest_path);
  CampaignStore store(store_path);
  write(log_path, logText(4, 0, 2, 3));
  const auto r = store.ingestLog(log_path, false);
  EXPECT_EQ(r.incomplete, std::vector<int>{2});
  EXPECT_EQ(r.evaluated, (std::vector<int>{1, 3, 4}));
  const auto s = store.status();
  EXPECT_NE(s.cycles[1].reason.find("position 3: 2 points"), std::string::npos) << s.cycles[1].reason;
}

TEST_F(Fixture, LogOfAnotherPlanIsRefusedAndTheStoreUntouched) {
  CampaignStore::create(store_path, manifest_path);
  {
    CampaignStore store(store_path);
    write(log_path, logText(2));
    store.ingestLog(log_path, false);
  }
  const std::string before = CampaignStore(store_path).exportErrorsCsv();
  const std::string other = (dir / "other.log").string();
  write(other, logText(3, 25.0));
  CampaignStore store(store_path);
  try {
    store.ingestLog(other, false);
    FAIL() << "a log of another plan was ingested";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("does not match the manifest"), std::string::npos) << e.what();
  }
  EXPECT_EQ(store.exportErrorsCsv(), before);
  EXPECT_EQ(store.status().points, 2 * static_cast<int>(manifest.points.size()));
}

TEST_F(Fixture, PointsLoggedTwiceAreRefused) {
  CampaignStore::create(store_path, manifest_path);
  CampaignStore store(store_path);
  write(log_path, logText(1));
  store.ingestLog(log_path, false);
  const std::string copy = (dir / "copy.log").string();
  write(copy, logText(1));
  EXPECT_THROW(store.ingestLog(copy, false), InputError);
}

TEST_F(Fixture, ReplacedLogIsRefused) {
  CampaignStore::create(store_path, manifest_path);
  CampaignStore store(store_path);
  const std::string text = logText(2);
  write(log_path, text);
  store.ingestLog(log_path, false);
  write(log_path, text.substr(0, text.size() / 2));  // truncated
  EXPECT_THROW(store.ingestLog(log_path, false), InputError);
  std::string changed = text;
  changed[changed.size() - 3] = changed[changed.size() - 3] == '1' ? '2' : '1';  // the last ingested line rewritten
  write(log_path, changed + "PT 3 1 1 0 0 0\n");
  EXPECT_THROW(store.ingestLog(log_path, false), InputError);
}

TEST_F(Fixture, StoreOfANewerSchemaIsRefusedUntouched) {
  CampaignStore::create(store_path, manifest_path);
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(store_path.c_str(), &db), SQLITE_OK);
    const std::string newer = "PRAGMA user_version = " + std::to_string(kStoreSchemaVersion + 1);
    ASSERT_EQ(sqlite3_exec(db, newer.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(db);
  }
  const std::string before = bytesOf(store_path);
  try {
    CampaignStore store(store_path);
    FAIL() << "a store of a newer schema was opened";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("schema version " + std::to_string(kStoreSchemaVersion + 1)), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(bytesOf(store_path), before);
}

TEST_F(Fixture, AVersion1StoreIsReadAndGainsTheLiveTablesWhenTheLiveLoopAsks) {
  CampaignStore::create(store_path, manifest_path);
  {  // what a store written by schema 1 looks like: no live-loop tables
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(store_path.c_str(), &db), SQLITE_OK);
    for (const char* t : {"talc_config", "predictions", "talc_ticks", "residuals", "talc_measurements", "talc_events",
                          "models", "phases", "talc_input_requests", "talc_input_changes"})
      ASSERT_EQ(sqlite3_exec(db, (std::string("DROP TABLE ") + t).c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << t;
    ASSERT_EQ(sqlite3_exec(db, "PRAGMA user_version = 1; UPDATE meta SET value = '1' WHERE key = 'schema_version'",
                           nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(db);
  }
  write(log_path, logText(2));
  CampaignStore store(store_path);
  store.ingestLog(log_path, true);
  EXPECT_EQ(store.status().schema_version, 1);
  store.upgradeToLiveSchema();
  EXPECT_EQ(store.status().schema_version, 2);
  auto q = store.database().prepare("SELECT COUNT(*) FROM talc_ticks");
  ASSERT_TRUE(q.step());
  EXPECT_EQ(q.integer(0), 0);
  EXPECT_EQ(store.status().cycles.size(), 2u);  // what schema 1 held is kept
}

TEST_F(Fixture, OtherFilesAreNotStores) {
  write(log_path, logText(1));
  EXPECT_THROW(CampaignStore{log_path}, InputError);
  EXPECT_THROW(CampaignStore{(dir / "absent.campaign").string()}, InputError);
  CampaignStore::create(store_path, manifest_path);
  EXPECT_THROW(CampaignStore::create(store_path, manifest_path), InputError);  // created once
}

TEST_F(Fixture, InputsFollowedInPiecesExportAsWritten) {
  CampaignStore::create(store_path, manifest_path);
  CampaignStore store(store_path);
  const std::string inputs = (dir / "inputs.csv").string();
  const std::string text = "# a data logger\ntime_s,T_env_C,c_rpm\n0,20.5,0\n60,20.51,100\n120,20.53,100\n180,20.6,0\n";
  write(inputs, text.substr(0, 10));  // inside the comment
  EXPECT_EQ(store.ingestInputs(inputs), 0);
  append(inputs, text.substr(10, 33));  // the comment, the header, a torn row
  EXPECT_EQ(store.ingestInputs(inputs), 0);
  append(inputs, text.substr(43));
  EXPECT_EQ(store.ingestInputs(inputs), 4);
  EXPECT_EQ(store.exportInputsCsv(), text);
  append(inputs, "170,20.7,0\n");  // the logger's clock went back
  try {
    store.ingestInputs(inputs);
    FAIL() << "a time going backwards was ingested";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(":7: time_s 170 does not follow"), std::string::npos) << e.what();
  }
  EXPECT_EQ(store.exportInputsCsv(), text);
}

}  // namespace
}  // namespace probeloop::campaign
