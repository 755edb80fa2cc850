// The reader's warnings in evaluation.json and report.md (issue 34 item 4): nothing added without
// warnings (the outputs stay byte for byte), and with them only the key and the section.
#include "evaluate/input_warnings.hpp"

#include <gtest/gtest.h>

namespace probeloop::evaluate {
namespace {

// As the evaluation writers dump their JSON: ordered keys, indent 1, a final newline.
const std::string kJson = "{\n \"piece\": \"ttp\",\n \"value_um\": 0.1,\n \"small\": 1e-05,\n \"none\": null,\n \"n\": 3\n}\n";

TEST(InputWarnings, NothingIsAddedWithoutWarnings) {
  EXPECT_EQ(withInputWarnings(kJson, {}), kJson);
  EXPECT_EQ(withInputWarningsSection("# Report\n\ntext\n", {}), "# Report\n\ntext\n");
  EXPECT_EQ(inputWarningLines({}), "");
}

TEST(InputWarnings, TheKeyComesLastAndTheRestKeepsItsText) {
  const std::vector<InputWarning> ws = {{"a.qif", 7, "WholePointSetId: no MeasuredPointSet with id 4; left unassigned"}};
  const std::string j = withInputWarnings(kJson, ws);
  // Every earlier line unchanged (order, number texts, null), then the array.
  const std::string head = kJson.substr(0, kJson.size() - 3);  // without "\n}\n"
  ASSERT_EQ(j.rfind(head, 0), 0u) << j;
  EXPECT_EQ(j.substr(head.size()),
            ",\n \"input_warnings\": [\n  {\n   \"file\": \"a.qif\",\n   \"line\": 7,\n   \"what\": \"WholePointSetId: no MeasuredPointSet "
            "with id 4; left unassigned\"\n  }\n ]\n}\n");
  const std::string md = withInputWarningsSection("# Report\n\ntext", ws);
  EXPECT_EQ(md.rfind("# Report\n\ntext\n\n## Input warnings\n\n", 0), 0u) << md;
  EXPECT_NE(md.find("- `a.qif` line 7: WholePointSetId: no MeasuredPointSet with id 4; left unassigned\n"), std::string::npos) << md;
  EXPECT_EQ(inputWarningLines(ws), "warning: a.qif:7: WholePointSetId: no MeasuredPointSet with id 4; left unassigned\n");
}

// A warning --strict does not refuse (a feature stated without points in a file of points):
// report.md must not claim --strict would refuse the file. Alone: its own intro; beside a reader's
// warning: the reader's intro, and the other line marked.
TEST(InputWarnings, ASectionSaysWhichWarningsStrictKeeps) {
  const InputWarning unused{"a.qif", 9, "feature Z3 states its measured geometry but no points", false};
  const InputWarning lenient{"a.qif", 7, "WholePointSetId: no MeasuredPointSet with id 4; left unassigned"};
  const std::string alone = withInputWarningsSection("# R\n", {unused});
  EXPECT_EQ(alone.find("`--strict` refuses the file instead"), std::string::npos) << alone;
  EXPECT_NE(alone.find("the file's meaning is whole, so `--strict` does not refuse it.\n\n"
                       "- `a.qif` line 9: feature Z3 states its measured geometry but no points\n"),
            std::string::npos)
      << alone;
  const std::string both = withInputWarningsSection("# R\n", {lenient, unused});
  EXPECT_NE(both.find("`--strict` refuses the file instead. Lines marked (kept under `--strict`) are what the file holds"),
            std::string::npos)
      << both;
  EXPECT_NE(both.find("- `a.qif` line 7: WholePointSetId: no MeasuredPointSet with id 4; left unassigned\n"), std::string::npos);
  EXPECT_NE(both.find("- `a.qif` line 9: feature Z3 states its measured geometry but no points (kept under `--strict`)\n"),
            std::string::npos);
  // evaluation.json and stdout carry it as any other.
  EXPECT_EQ(inputWarningLines({unused}), "warning: a.qif:9: feature Z3 states its measured geometry but no points\n");
}

TEST(InputWarnings, FromADocument) {
  interop::CmmDocument d;
  d.file = "x.dmo";
  d.warnings = {{3, "statements after ENDFIL; passed over"}};
  const auto ws = inputWarnings(d);
  ASSERT_EQ(ws.size(), 1u);
  EXPECT_EQ(inputWarningText(ws[0]), "x.dmo:3: statements after ENDFIL; passed over");
}

}  // namespace
}  // namespace probeloop::evaluate
