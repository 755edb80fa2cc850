// DMIS programs and output (interop/dmis.hpp): what we write reads back to the same features
// and points, keeps its lines within 80 characters and its moves vertical or at the clearance
// height; output as other packages write it (GEOPAK's direction angles, the DMSC demo, a Trimek
// sphere without INNER/OUTER, lower case, continuations, CRLF, inches) reads; bad files are
// refused with file:line.
#include "interop/dmis.hpp"

#include <gtest/gtest.h>

#include <sstream>

#include "core/error.hpp"
#include "interop/test_documents.hpp"

namespace probeloop::interop {
namespace {

CmmDocument plan() { return testing::ballPlaneBore(); }

TEST(Dmis, AProgramReadsBackToItsFeaturesAndPoints) {
  const auto a = plan();
  const std::string text = dmisProgram(a, "TEST PLAN");
  const auto b = parseDmisProgram(text, "plan.dmi");
  testing::expectSamePlan(a, b, 1e-6);  // vectors written to 6 decimals
  EXPECT_NEAR(b.features[0].nominal.diameter_mm, 25, 1e-9);
  EXPECT_NEAR(b.features[2].nominal.diameter_mm, 20, 1e-9);
  EXPECT_EQ(text.rfind("DMISMN/'TEST PLAN',05.2\n", 0), 0u);
  EXPECT_NE(text.find("\nMEAS/CYLNDR,F(BORE1),6\n"), std::string::npos);
  EXPECT_NE(text.find("\nENDFIL\n"), std::string::npos);
  EXPECT_EQ(text, dmisProgram(a, "TEST PLAN"));
}

// Every physical line within 80 characters; every move vertical or at the clearance height
// (above every point), so that no move crosses the part between two probed points.
TEST(Dmis, TheProgramsMovesAreVerticalOrAtTheClearanceHeight) {
  const std::string text = dmisProgram(plan(), "TEST PLAN");
  std::istringstream in(text);
  std::string joined, line;
  std::vector<Eigen::Vector3d> moves;
  while (std::getline(in, line)) {
    EXPECT_LE(line.size(), 80u) << line;
    if (!line.empty() && line.back() == '$') {
      joined += line.substr(0, line.size() - 1);
      continue;
    }
    joined += line;
    if (joined.rfind("GOTO/", 0) == 0) {
      double x, y, z;
      ASSERT_EQ(std::sscanf(joined.c_str(), "GOTO/%lf,%lf,%lf", &x, &y, &z), 3) << joined;
      moves.emplace_back(x, y, z);
    }
    joined.clear();
  }
  ASSERT_EQ(moves.size(), 3u * 15);  // up, down, (PTMEAS), up per point
  double clear = -1e9;
  for (const auto& m : moves) clear = std::max(clear, m.z());
  EXPECT_NEAR(clear, 25 + 5 + 20, 1e-9);  // the sphere's top point + 5 mm approach + 20 mm
  for (std::size_t i = 1; i < moves.size(); ++i) {
    const bool vertical = (moves[i].head<2>() - moves[i - 1].head<2>()).norm() < 1e-9;
    const bool at_clearance = moves[i].z() == clear && moves[i - 1].z() == clear;
    EXPECT_TRUE(vertical || at_clearance) << i << ": " << moves[i - 1].transpose() << " -> " << moves[i].transpose();
  }
}

TEST(Dmis, OutputReadsBackToMeasuredFeaturesWithTheirPoints) {
  auto r = plan();
  for (auto& f : r.features) {
    f.measured = f.nominal;
    f.measured.location_mm += Eigen::Vector3d(0.001, -0.002, 0.0005);
    for (auto& p : f.points) p.p_mm += 0.0013 * p.normal;
  }
  r.features[0].measured.given = false;  // a feature without a fit: points only
  const auto d = parseDmisOutput(dmisOutput(r, "RUN"), "run.dmo");
  ASSERT_EQ(d.features.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(d.features[i].name, r.features[i].name);
    EXPECT_EQ(d.features[i].kind, r.features[i].kind);
    EXPECT_EQ(d.features[i].measured.given, i > 0);
    ASSERT_EQ(d.features[i].points.size(), r.features[i].points.size());
    for (std::size_t k = 0; k < r.features[i].points.size(); ++k)
      EXPECT_LT((d.features[i].points[k].p_mm - r.features[i].points[k].p_mm).norm(), 1e-6);
  }
  EXPECT_LT((d.features[1].measured.location_mm - r.features[1].measured.location_mm).norm(), 1e-6);
  EXPECT_TRUE(d.features[2].internal);
  EXPECT_GT(d.features[0].line, 0);
}

// As other packages write it: GEOPAK (direction angles in degrees, continued lines, a point
// without a vector), the DMSC demo (FILNAM, tolerances, datums), a Trimek sphere without
// INNER/OUTER; in lower case with CRLF and in inches.
TEST(Dmis, OtherPackagesOutputReads) {
  const std::string geopak =
      "$$ Data from GEOPAK Copyright (c) 2004 Mitutoyo Messgeraete GmbH\r\n"
      "FA(FeatureID_1) = FEAT/PLANE, CART,$\r\n"
      "0.000037832313, -0.392125000586, -2.140539040020,$\r\n"
      "179.991497992475, 90.008501976792, 90.000022920378\r\n"
      "FA(FeatureID_3) = FEAT/POINT, CART, 3.349968393187, -1.313496902315, -1.431274697897, 0, 0, 0\r\n";
  const auto g = parseDmisOutput(geopak, "geopak.dmo");
  ASSERT_EQ(g.features.size(), 2u);
  EXPECT_EQ(g.features[0].name, "FEATUREID_1");
  EXPECT_EQ(g.features[0].kind, CmmFeatureKind::Plane);
  EXPECT_EQ(g.features[0].line, 2);
  EXPECT_LT((g.features[0].measured.direction - Eigen::Vector3d(-1, 0, 0)).norm(), 1e-3);
  EXPECT_NEAR(g.features[0].measured.location_mm.z(), -2.140539040020, 1e-12);
  EXPECT_EQ(g.features[1].kind, CmmFeatureKind::Point);
  ASSERT_EQ(g.features[1].points.size(), 1u);
  const std::string dmsc =
      "FILNAM/'cpp.qif',5.3\nUNITS/MM,ANGDEC\nOUTPUT/FA(DAT_A),TA(FLAT1)\nFA(DAT_A)=FEAT/PLANE,CART,0,0,0,0,0,1\n"
      "TA(FLAT1)=TOL/FLAT,0.023,INTOL\nDATDEF/FA(DAT_A),DAT(A)\nfa(esfera_10)=feat/sphere,cart,74.8580,58.0652,3.7478,27.8511\nENDFIL\n";
  const auto m = parseDmisOutput(dmsc, "dmsc.dmo");
  ASSERT_EQ(m.features.size(), 2u);
  EXPECT_EQ(m.features[1].name, "ESFERA_10");
  EXPECT_NEAR(m.features[1].measured.diameter_mm, 27.8511, 1e-12);
  ASSERT_EQ(m.notes.size(), 3u) << m.notes.front();  // DATDEF, OUTPUT, TA()=TOL: passed over, counted
  const auto inch = parseDmisOutput("FILNAM/'x'\nUNITS/INCH,ANGDEC\nFA(P)=FEAT/POINT,CART,1,2,3,0,0,1\n", "inch.dmo");
  ASSERT_EQ(inch.features.size(), 1u);
  EXPECT_LT((inch.features[0].measured.location_mm - Eigen::Vector3d(25.4, 50.8, 76.2)).norm(), 1e-12);
  EXPECT_EQ(inch.length_unit, "inch");
}

void expectRefused(const std::string& text, const std::string& want, bool program = true) {
  try {
    program ? parseDmisProgram(text, "bad.dmi") : parseDmisOutput(text, "bad.dmo");
    ADD_FAILURE() << "accepted; expected '" << want << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
  }
}

// Lenient (issue 34): an output without ENDFIL is read with a warning at its last statement,
// statements after ENDFIL are passed over with a warning at the first; strict refuses both there.
TEST(Dmis, AMissingEndfilAndStatementsAfterItAreWarned) {
  const std::string body = "FILNAM/'x'\nFA(P1)=FEAT/POINT,CART,1,2,3,0,0,1\n";
  const auto cut = parseDmisOutput(body, "cut.dmo");
  ASSERT_EQ(cut.warnings.size(), 1u);
  EXPECT_EQ(cut.warnings[0].line, 2);
  EXPECT_EQ(cut.warnings[0].what, "no ENDFIL after the last statement (the file may be cut short); what is there was read");
  ASSERT_EQ(cut.features.size(), 1u);
  const auto after = parseDmisOutput(body + "ENDFIL\nFA(P2)=FEAT/POINT,CART,4,5,6,0,0,1\n", "after.dmo");
  ASSERT_EQ(after.warnings.size(), 1u);
  EXPECT_EQ(after.warnings[0].line, 4);
  EXPECT_EQ(after.features.size(), 1u);  // P2 passed over
  EXPECT_TRUE(parseDmisOutput(body + "ENDFIL\n", "ok.dmo").warnings.empty());
  for (const auto& [text, want] : {std::pair<std::string, std::string>{body, "cut.dmo:2: no ENDFIL after the last statement (the file may be cut short)"},
                                   {body + "ENDFIL\nFA(P2)=FEAT/POINT,CART,4,5,6,0,0,1\n", "cut.dmo:4: statements after ENDFIL"}}) {
    try {
      parseDmisOutput(text, "cut.dmo", CmmReadOptions{true});
      ADD_FAILURE() << "strict read accepted: " << want;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), want);
    }
  }
}

void expectStrictRefusal(const std::string& text, const std::string& file, const std::string& want, bool program) {
  try {
    if (program) parseDmisProgram(text, file, CmmReadOptions{true});
    else parseDmisOutput(text, file, CmmReadOptions{true});
    ADD_FAILURE() << "strict read accepted: " << want;
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(want, 0), 0u) << e.what();
  }
}

// Lenient programs (issue 34 item 2): a label defined again (the later definition read), a MEAS
// block whose ENDMES is missing but whose count adds up (closed at the next MEAS), a stray
// ENDMES and a statement after ENDFIL are read with a warning at their line; strict refuses
// the first of them there.
TEST(Dmis, AProgramsFormMistakesAreWarned) {
  const std::string text =
      "DMISMN/'x',05.2\n"                  // 1
      "F(A)=FEAT/PLANE,CART,0,0,0,0,0,1\n"  // 2
      "F(A)=FEAT/PLANE,CART,0,0,5,0,0,1\n"  // 3: defined again
      "MEAS/PLANE,F(A),1\n"                 // 4
      "PTMEAS/CART,1,2,5,0,0,1\n"           // 5
      "MEAS/PLANE,F(A),1\n"                 // 6: the block of line 4 had no ENDMES
      "PTMEAS/CART,3,4,5,0,0,1\n"           // 7
      "ENDMES\n"                            // 8
      "ENDMES\n"                            // 9: without MEAS
      "ENDFIL\n"                            // 10
      "GOTO/0,0,100\n";                     // 11: after ENDFIL
  const auto d = parseDmisProgram(text, "odd.dmi");
  ASSERT_EQ(d.features.size(), 1u);
  EXPECT_EQ(d.features[0].nominal.location_mm.z(), 5.0);  // the later definition
  ASSERT_EQ(d.features[0].points.size(), 1u);             // the second block's point
  EXPECT_EQ(d.features[0].points[0].p_mm, Eigen::Vector3d(3, 4, 5));
  EXPECT_EQ(d.moves.size(), 2u);  // the PTMEAS; the GOTO after ENDFIL passed over
  ASSERT_EQ(d.warnings.size(), 4u);
  const std::vector<std::pair<int, std::string>> want = {
      {3, "F(A) defined again (first at line 2); the later definition read"},
      {6, "the MEAS block of line 4 has no ENDMES; closed before the MEAS of this line (its 1 PTMEAS as announced)"},
      {9, "ENDMES without MEAS; passed over"},
      {11, "statements after ENDFIL; passed over"}};
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(d.warnings[i].line, want[i].first);
    EXPECT_EQ(d.warnings[i].what, want[i].second);
  }
  expectStrictRefusal(text, "odd.dmi", "odd.dmi:3: F(A) defined again (first at line 2)", true);
  // The block closed at ENDFIL, and a program without ENDFIL.
  const auto e = parseDmisProgram("DMISMN/'x'\nF(A)=FEAT/PLANE,CART,0,0,0,0,0,1\nMEAS/PLANE,F(A),1\nPTMEAS/CART,0,0,0,0,0,1\n", "cut.dmi");
  ASSERT_EQ(e.warnings.size(), 2u);
  EXPECT_EQ(e.warnings[0].what, "the MEAS block of line 3 has no ENDMES; closed at the end of the file (its 1 PTMEAS as announced)");
  EXPECT_EQ(e.warnings[1].line, 4);
  EXPECT_EQ(e.features[0].points.size(), 1u);
  EXPECT_TRUE(parseDmisProgram("DMISMN/'x'\nF(A)=FEAT/PLANE,CART,0,0,0,0,0,1\nMEAS/PLANE,F(A),1\nPTMEAS/CART,0,0,0,0,0,1\nENDMES\nENDFIL\n",
                               "ok.dmi").warnings.empty());
}

// Lenient outputs: a feature or a point reported again is read from its later report, with a
// warning; another kind under the same label stays refused (another meaning).
TEST(Dmis, AnOutputsLabelReportedAgainKeepsTheLaterReport) {
  const std::string text =
      "FILNAM/'x'\n"                                    // 1
      "FA(C)=FEAT/CYLNDR,INNER,CART,0,0,0,0,0,1,10\n"   // 2
      "FA(C_P01)=FEAT/POINT,CART,5,0,0,1,0,0\n"          // 3
      "FA(C_P01)=FEAT/POINT,CART,5.1,0,0,1,0,0\n"        // 4: re-taken
      "FA(C)=FEAT/CYLNDR,INNER,CART,0,0,0,0,0,1,10.2\n"  // 5: reported again
      "ENDFIL\n";
  const auto d = parseDmisOutput(text, "again.dmo");
  ASSERT_EQ(d.features.size(), 1u);
  EXPECT_EQ(d.features[0].measured.diameter_mm, 10.2);
  ASSERT_EQ(d.features[0].points.size(), 1u);
  EXPECT_EQ(d.features[0].points[0].p_mm.x(), 5.1);
  ASSERT_EQ(d.warnings.size(), 2u);
  EXPECT_EQ(d.warnings[0].line, 4);
  EXPECT_EQ(d.warnings[0].what, "FA(C_P01) reported again (first at line 3); the later one read");
  EXPECT_EQ(d.warnings[1].line, 5);
  expectStrictRefusal(text, "again.dmo", "again.dmo:4: FA(C_P01) reported again (first at line 3)", false);
  expectRefused("FILNAM/'x'\nFA(X)=FEAT/PLANE,CART,0,0,0,0,0,1\nFA(X)=FEAT/SPHERE,OUTER,CART,0,0,0,5\nENDFIL\n",
                "bad.dmo:3: FA(X)=FEAT/: a sphere, but line 2 makes X a plane", false);
}

TEST(Dmis, RefusesWhatDoesNotAddUp) {
  const std::string f = "DMISMN/'x',05.2\nF(A)=FEAT/PLANE,CART,0,0,0,0,0,1\n";
  expectRefused(f + "MEAS/PLANE,F(A),3\nPTMEAS/CART,0,0,0,0,0,1\nENDMES\n", "bad.dmi:3: MEAS/..,F(A),3: 1 PTMEAS in the block");
  expectRefused(f + "PTMEAS/CART,0,0,0,0,0,1\n", "bad.dmi:3: PTMEAS outside a MEAS block");
  expectRefused(f + "MEAS/PLANE,F(A),2\nPTMEAS/CART,0,0,0,0,0,1\n", "bad.dmi:3: MEAS: no ENDMES, and 1 PTMEAS where MEAS/..,F(A),2 announced");
  expectRefused(f + "MEAS/PLANE,F(A),2\nPTMEAS/CART,0,0,0,0,0,1\nMEAS/PLANE,F(A),1\n",
                "bad.dmi:3: MEAS: no ENDMES, and 1 PTMEAS where MEAS/..,F(A),2 announced");
  expectRefused(f + "MEAS/PLANE,F(B),1\n", "bad.dmi:3: MEAS: F(B) is not defined");
  expectRefused(f + "MEAS/PLANE,F(A),1\nPTMEAS/CART,0,0,1O,0,0,1\nENDMES\n", "bad.dmi:4: PTMEAS: '1O' is not a number");
  expectRefused("FILNAM/'x'\nFA(A)=FEAT/PLANE,CART,0,0,0\n", "bad.dmo:2: FEAT/PLANE: expected i,j,k", false);
  expectRefused("FILNAM/'x'\nUNITS/FURLONG,ANGDEC\n", "bad.dmo:2: UNITS/FURLONG", false);
  // Hostile or malformed: a FEAT inside a MEAS block (it would move the block's feature), a
  // count beyond the bound, a FEAT without its label, a feature with two kinds, a zero normal.
  expectRefused(f + "MEAS/PLANE,F(A),1\nF(B)=FEAT/PLANE,CART,0,0,0,0,0,1\nPTMEAS/CART,0,0,0,0,0,1\nENDMES\n",
                "bad.dmi:4: FEAT inside the MEAS block of line 3");
  expectRefused(f + "MEAS/PLANE,F(A),1E30\n", "bad.dmi:3: MEAS point count: a whole number from 1 to 100000000");
  expectRefused("FILNAM/'x'\nFA()=FEAT/POINT,CART,0,0,0\n", "bad.dmo:2: a FEAT statement without its label", false);
  expectRefused("FILNAM/'x'\nFA(X=FEAT/POINT,CART,0,0,0\n", "bad.dmo:2: a FEAT statement without its label", false);
  expectRefused("FILNAM/'x'\nF(X)=FEAT/PLANE,CART,0,0,0,0,0,1\nFA(X)=FEAT/CYLNDR,INNER,CART,0,0,0,0,0,1,5\n",
                "bad.dmo:3: FA(X)=FEAT/: a cylinder, but line 2 makes X a plane", false);
  expectRefused("FILNAM/'x'\nFA(X)=FEAT/PLANE,CART,0,0,0,0,0,0\n", "bad.dmo:2: FEAT/PLANE: i,j,k is a zero vector", false);
}

// Cosines that are not a unit vector are normalised, not taken for direction angles; a program
// is told from output by its first statement.
TEST(Dmis, VectorsAndKinds) {
  const auto d = parseDmisOutput("FILNAM/'x'\nFA(X)=FEAT/PLANE,CART,0,0,0,0,0,2\n", "v.dmo");
  ASSERT_EQ(d.features.size(), 1u);
  EXPECT_LT((d.features[0].measured.direction - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  EXPECT_TRUE(isDmisProgram("$$ c\nDMISMN/'x',05.2\nENDFIL\n"));
  EXPECT_FALSE(isDmisProgram("FILNAM/'x'\n$$ MEAS/PLANE,F(A),1\nENDFIL\n"));
  EXPECT_TRUE(looksLikeDmis("FILNAM/'x'\n"));
  EXPECT_EQ(parseDmisProgram("DMISMN/'x'\nUNITS/INCH,ANGDEC\nENDFIL\n", "i.dmi").length_unit, "inch");
}

}  // namespace
}  // namespace probeloop::interop
