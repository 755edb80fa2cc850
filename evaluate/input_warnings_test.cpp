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
