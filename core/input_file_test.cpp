// The one input-opening rule (core/input_file.hpp), the all-or-nothing outputs
// (core/atomic_file.hpp) and the clipped messages (core/error.hpp), issue 28.
#include "core/input_file.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "core/atomic_file.hpp"
#include "core/error.hpp"

namespace probeloop {
namespace {

namespace fs = std::filesystem;

class InputFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("probeloop_input_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write(const std::string& name, const std::string& bytes) const {
    std::ofstream(path(name), std::ios::binary) << bytes;
    return path(name);
  }
  // The InputError's message, or "" if readFile succeeded.
  static std::string refusal(const std::string& p, const InputLimit& limit = kAnyInput) {
    try {
      readFile(p, limit);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

void expectHas(const std::string& text, const std::string& want) {
  EXPECT_NE(text.find(want), std::string::npos) << "'" << want << "' not in: " << text;
}

TEST_F(InputFile, WhatIsNotARegularFileIsRefusedAtOnceNamingThePath) {
  const std::string fifo = path("pipe.csv");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  const std::string e = refusal(fifo);  // no writer: an ordinary open would block for ever
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
  expectHas(e, fifo + ": is a named pipe (FIFO)");
  expectHas(refusal(dir_.string()), dir_.string() + ": is a folder, not a file");
  expectHas(refusal("/dev/zero"), "/dev/zero: is a device");
  fs::create_symlink(path("b"), path("a"));
  fs::create_symlink(path("a"), path("b"));
  expectHas(refusal(path("a")), path("a") + ": is a loop of symbolic links");
  fs::create_symlink(path("nowhere"), path("dangling"));
  expectHas(refusal(path("dangling")), "is a symbolic link to nothing");
  expectHas(refusal(path("missing.yaml")), path("missing.yaml") + ": does not exist");
  // A link to a regular file is that file.
  write("real.txt", "x,y\n");
  fs::create_symlink(path("real.txt"), path("link.txt"));
  EXPECT_EQ(readFile(path("link.txt")), "x,y\n");
  EXPECT_EQ(regularFileProblem(path("link.txt")), "");
  expectHas(regularFileProblem(fifo), "named pipe");
}

TEST_F(InputFile, AFileAboveItsFormatsCapIsRefusedBeforeItIsRead) {
  const std::string p = write("big.yaml", std::string(3000, 'a'));
  const InputLimit small{2048, "a test file"};
  const std::string e = refusal(p, small);
  expectHas(e, p + ": the file has 3000 bytes, more than the 2048 bytes a test file may have");
  EXPECT_EQ(readFile(p, InputLimit{3000, "a test file"}).size(), 3000u);  // exactly at the cap: read
}

TEST_F(InputFile, Utf8WithOrWithoutBomIsReadAndTheBomDropped) {
  EXPECT_EQ(readFile(write("plain.csv", "a,b\n1,2\n")), "a,b\n1,2\n");
  EXPECT_EQ(readFile(write("bom.csv", "\xEF\xBB\xBF" "a,b\n")), "a,b\n");
  EXPECT_EQ(readFile(write("empty.csv", "")), "");
}

// UTF-16 with a byte-order mark, as Windows CMM software writes it: transcoded to UTF-8,
// characters outside the BMP (surrogate pairs) included, the XML declaration relabelled.
TEST_F(InputFile, Utf16WithBomIsTranscoded) {
  const std::u16string text = u"<?xml version=\"1.0\" encoding=\"UTF-16\"?>\n<a>\u00b5m \U0001D70E</a>\n";
  std::string le = "\xFF\xFE", be = "\xFE\xFF";
  for (char16_t c : text) {
    le += static_cast<char>(c & 0xFF), le += static_cast<char>(c >> 8);
    be += static_cast<char>(c >> 8), be += static_cast<char>(c & 0xFF);
  }
  const std::string want = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<a>\xC2\xB5m \xF0\x9D\x9C\x8E</a>\n";
  EXPECT_EQ(readFile(write("le.qif", le)), want);
  std::string single = "\xFF\xFE";
  for (char c : std::string("<?xml version='1.0' encoding = 'utf-16le'?><a/>")) single += c, single += '\0';
  EXPECT_EQ(readFile(write("single.qif", single)), "<?xml version='1.0' encoding = 'UTF-8'?><a/>");
  EXPECT_EQ(readFile(write("be.qif", be)), want);
  expectHas(refusal(write("odd.csv", le + "x")), "UTF-16LE (byte-order mark) but has an odd number of bytes");
  expectHas(refusal(write("lone.csv", std::string("\xFF\xFE\x00\xD8\x41\x00", 6))), "lone surrogate");
}

TEST_F(InputFile, OtherEncodingsAndBinaryAreRefusedNamingThem) {
  expectHas(refusal(write("u32.csv", std::string("\xFF\xFE\x00\x00" "a\0\0\0", 8))), "UTF-32LE");
  expectHas(refusal(write("u16.csv", std::string("a\0,\0b\0", 6))), "UTF-16LE text without a byte-order mark");
  expectHas(refusal(write("u16be.csv", std::string("\0a\0,\0b", 6))), "UTF-16BE text without a byte-order mark");
  expectHas(refusal(write("bin.ply", std::string("ply\n\x01\x00\x02", 7))), "a NUL byte at byte 5: the file looks like binary data");
}

TEST(DescribeContent, NamesTheKindsProbeloopMeets) {
  EXPECT_EQ(describeContent("<?xml version=\"1.0\"?>\n<QIFDocument xmlns=\"http://qifstandards.org/xsd/qif3\">"),
            "a QIF (XML) document");
  EXPECT_EQ(describeContent("<?xml version=\"1.0\"?>\n<!DOCTYPE QIFDocument [<!ENTITY a \"b\">]>\n<QIFDocument>"),
            "a QIF (XML) document");
  EXPECT_EQ(describeContent("{\n  \"format\": \"probeloop-plan-manifest\",\n  \"kind\": \"sphere_artifact\"}"),
            "a JSON document (kind: sphere_artifact)");
  EXPECT_EQ(describeContent("DMISMN/'plan',05.0\n"), "a DMIS file");
  EXPECT_EQ(describeContent("PT 1 1 1 10.0 20.0 30.0\n"), "a probe log (PT lines)");
  EXPECT_EQ(describeContent("%\nSTART 20260101 000000\nPT 1 1 1 1. 2. 3.\n"), "a probe log (PT lines)");
  EXPECT_EQ(describeContent("# machine\nname: NMV\nkind: machine\n"), "a YAML description (kind: machine)");
  EXPECT_EQ(describeContent("%\nO1000\nG21 G90\n"), "a G-code program");
  EXPECT_EQ(describeContent("(sphere cycle)\nG21 G90\n"), "a G-code program");
  EXPECT_EQ(describeContent("feature,point,x_mm\n"), "a CSV table (first line 'feature,point,x_mm')");
  EXPECT_EQ(describeContent(""), "an empty file");
  EXPECT_EQ(describeContent("hello world\n"), "");
  EXPECT_EQ(describeContent("{ \"kind\" : \"machine_truth\", \"x\": 1}"), "a JSON document (kind: machine_truth)");
  EXPECT_EQ(describeContent("N10 G0 X1. Y2.\n"), "a G-code program");
  EXPECT_EQ(describeContent("N10 X1, Y2\n"), "a CSV table (first line 'N10 X1, Y2')");
  EXPECT_EQ(describeContent("title: a model\nkind: gum_model\r\n"), "a YAML description (kind: gum_model)");
  EXPECT_EQ(describeContent("title: a model\n"), "a YAML document");
  // probeloop's own tables, named by their header.
  EXPECT_EQ(describeContent("# probeloop evaluate\ntime_s,cycle,EX0C_um,U_EX0C_um\n1,1,0.5,0.2\n"),
            "an errors.csv of `probeloop evaluate` (first line 'time_s,cycle,EX0C_um,U_EX0C_um')");
  EXPECT_EQ(describeContent("time_s,T_env_C,c_rpm\n0,20,0\n"),
            "an inputs.csv of logged machine inputs (first line 'time_s,T_env_C,c_rpm')");
  EXPECT_EQ(describeContent("time_s,cycle,c_deg,feature,point,x_mm,y_mm,z_mm\n"),
            "a points CSV (first line 'time_s,cycle,c_deg,feature,point,x_mm,y_mm,z_mm')");
  EXPECT_EQ(describeContent("time_s,cycle_count\n"), "a CSV table (first line 'time_s,cycle_count')");  // not 'cycle'
}

// A hostile token (a 5 MB line) is echoed in a few dozen characters, with its length.
TEST(ClipMessage, LongTokensAndMessagesAreCut) {
  const std::string token(5'000'000, 'x');
  const InputError e("f.log", 3, "unrecognised log line '" + token + "'");
  const std::string m = e.what();
  EXPECT_LT(m.size(), 200u);
  expectHas(m, "f.log:3: unrecognised log line 'xxxxx");
  expectHas(m, "...' (5000000 characters)");
  const std::string shortMsg = "word 'Q' is not modelled";
  EXPECT_EQ(clipMessage(shortMsg), shortMsg);  // ordinary messages unchanged
  const std::string many(10'000, 'y');
  const std::string cut = clipMessage(many);
  EXPECT_LT(cut.size(), 2100u);
  expectHas(cut, "(message cut at 2000 of 10000 characters)");
  // A cut never splits a UTF-8 character: 2-byte 'µ' repeated across the cut.
  std::string mu;
  for (int i = 0; i < 200; ++i) mu += "\xC2\xB5";
  // One ASCII byte first: byte 60 of the token is then a continuation byte, and the cut must
  // step back to 59.
  const std::string clipped = clipMessage("'x" + mu + "'");
  EXPECT_EQ(clipped.substr(0, 61), "'x" + mu.substr(0, 58) + ".");
  EXPECT_EQ(SafetyError("a '" + token + "'").what(), clipMessage("a '" + token + "'"));
  // Apostrophes inside words quote nothing: an alarm text of 150 characters stays whole.
  const std::string alarm = "program alarm #3000=1 (OPERATOR'S NOTE: " + std::string(150, 'n') + " CHECK THE STYLUS'S TIP)";
  EXPECT_EQ(clipMessage(alarm), alarm);
}

TEST_F(InputFile, ABatchCommitsAllOutputsOrNone) {
  const std::string a = path("out/a.csv"), b = path("out/b.json");
  writeFileAtomic(a, "old a");
  {
    OutputBatch batch;
    writeFileAtomic(a, "new a");
    writeFileAtomic(b, "new b");
    EXPECT_EQ(readFile(a), "new a");  // the command reads back what it wrote
    writeFileAtomic(a, "newer a");  // written twice: the later content, one temporary
    EXPECT_EQ(readFile(a), "newer a");
    // Nothing in place before the commit.
    std::ifstream in(a);
    std::string before((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(before, "old a");
    EXPECT_FALSE(fs::exists(b));
    batch.commit();
  }
  EXPECT_EQ(readFile(a), "newer a");
  EXPECT_EQ(readFile(b), "new b");
  {
    OutputBatch batch;
    writeFileAtomic(a, "failed a");
    writeFileAtomic(b, "failed b");
    // no commit: the command failed
  }
  EXPECT_EQ(readFile(a), "newer a");
  EXPECT_EQ(readFile(b), "new b");
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(path("out"))) files += e.is_regular_file();
  EXPECT_EQ(files, 2u);  // no temporary left behind
  // A write that fails inside a batch leaves the others' old versions too: a folder that cannot
  // be created, and a folder standing where an output goes (refused when staged, so that the
  // commit cannot stop half-way at its rename).
  fs::create_directories(path("out/scene.gltf"));
  for (const std::string& bad : {std::string("/proc/probeloop_cannot_write_here/x.gltf"), path("out/scene.gltf")}) {
    OutputBatch batch;
    writeFileAtomic(a, "third a");
    try {
      writeFileAtomic(bad, "scene");
      ADD_FAILURE() << "not refused: " << bad;
    } catch (const InputError& e) {
      expectHas(e.what(), bad + ": cannot");
    }
  }
  EXPECT_EQ(readFile(a), "newer a");
  EXPECT_THROW({ OutputBatch one; OutputBatch two; }, std::logic_error);
}

// campaign run --follow rewrites its controller file after every pass for another program to
// read (tools/linuxcnc_sim/live_offsets.py): a live write is in place at once, inside a batch,
// and stays when the batch is dropped; it leaves no temporary.
TEST_F(InputFile, ALiveWriteIsInPlaceAtOnceEvenInsideABatch) {
  const std::string live = path("out/controller.json"), other = path("out/dashboard.csv");
  {
    OutputBatch batch;
    writeLiveFileAtomic(live, "pass 1");
    writeFileAtomic(other, "batched");
    std::ifstream in(live);
    EXPECT_EQ(std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()), "pass 1");
    EXPECT_FALSE(fs::exists(other));
    writeLiveFileAtomic(live, "pass 2");
    // no commit
  }
  EXPECT_EQ(readFile(live), "pass 2");
  EXPECT_FALSE(fs::exists(other));
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(path("out"))) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);
  fs::create_directories(path("out/in_the_way.json"));
  EXPECT_THROW(writeLiveFileAtomic(path("out/in_the_way.json"), "x"), InputError);
}

}  // namespace
}  // namespace probeloop
