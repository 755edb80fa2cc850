// Text measurement models: grammar, derivatives against hand-written partials, and errors
// that point at the column.
#include "uncertainty/expression.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "uncertainty/gum.hpp"

namespace probeloop::uncertainty {
namespace {

TEST(Expression, PrecedenceAndAssociativity) {
  const std::vector<std::string> s = {"x", "y"};
  const double v[2] = {3, 2};
  EXPECT_DOUBLE_EQ(Expression::parse("1 + 2*x - y/4", s).evaluate(v), 1 + 6 - 0.5);
  EXPECT_DOUBLE_EQ(Expression::parse("2^3^2", s).evaluate(v), 512);     // right-associative
  EXPECT_DOUBLE_EQ(Expression::parse("-x^2", s).evaluate(v), -9);       // -(x^2)
  EXPECT_DOUBLE_EQ(Expression::parse("x^-1", s).evaluate(v), 1.0 / 3);  // folded constant exponent
  EXPECT_DOUBLE_EQ(Expression::parse("(x - y) * (x + y)", s).evaluate(v), 5);
  EXPECT_DOUBLE_EQ(Expression::parse("atan2(y, x) + hypot(x, y)", s).evaluate(v), std::atan2(2, 3) + std::hypot(3, 2));
  EXPECT_NEAR(Expression::parse("sin(pi/6) + 1e-3 * .5e3", s).evaluate(v), 1.0, 1e-15);
}

TEST(Expression, GradientMatchesThePartialDerivativesForManyInputs) {
  // 11 inputs: more than one chunk of the automatic differentiation.
  std::vector<std::string> names;
  std::vector<double> x;
  std::string text;
  for (int i = 0; i < 11; ++i) {
    names.push_back("x" + std::to_string(i));
    x.push_back(0.5 + i);
    text += (i ? " + " : "") + std::to_string(i + 1) + "*x" + std::to_string(i) + "^2";
  }
  text += " + sqrt(x3) * log(x10)";
  const auto e = Expression::parse(text, names);
  std::vector<double> g(11);
  const double y = e.gradient(x.data(), g);
  EXPECT_DOUBLE_EQ(y, e.evaluate(x.data()));
  for (int i = 0; i < 11; ++i) {
    double expected = 2.0 * (i + 1) * x[i];
    if (i == 3) expected += 0.5 / std::sqrt(x[3]) * std::log(x[10]);
    if (i == 10) expected += std::sqrt(x[3]) / x[10];
    EXPECT_NEAR(g[i], expected, 1e-12 * std::fabs(expected)) << i;
  }
  // A square of a negative input keeps its derivative (constant exponent).
  const double neg[1] = {-2};
  std::vector<double> g1(1);
  Expression::parse("x^2", {"x"}).gradient(neg, g1);
  EXPECT_DOUBLE_EQ(g1[0], -4);
}

TEST(Expression, EndGaugeAsTextGivesTheSameBudgetAsTheCxxModel) {
  Problem pr;
  pr.output = "l";
  pr.inputs = {Input::normal("l_s", 50.000623, 25e-6, 18), Input::normal("d", 215e-6, 9.7e-6, 25.6),
               Input::rectangular("alpha_s", 11.5e-6, 2e-6), Input::normal("theta", -0.1, 0.41),
               Input::normal("dalpha", 0, 0.58e-6, 50), Input::normal("dtheta", 0, 0.029, 2)};
  std::vector<std::string> names;
  std::vector<double> x;
  for (const auto& in : pr.inputs) names.push_back(in.name), x.push_back(in.value);
  const auto e = Expression::parse("l_s + d - l_s*(dalpha*theta + alpha_s*dtheta)", names);
  std::vector<double> g(x.size());
  const double y = e.gradient(x.data(), g);
  const auto text = gufFromGradient(pr, y, g, 0.99);
  const auto cxx = propagate<6>(pr, [](const auto* v) { return v[0] + v[1] - v[0] * (v[4] * v[3] + v[2] * v[5]); }, 0.99);
  EXPECT_DOUBLE_EQ(text.y, cxx.y);
  EXPECT_NEAR(text.u_c, cxx.u_c, 1e-18);
  EXPECT_DOUBLE_EQ(text.nu_eff, cxx.nu_eff);
  EXPECT_EQ(std::lround(text.U * 1e6), 93);
}

int errorColumn(const std::string& text, const std::vector<std::string>& names, std::string* what = nullptr) {
  try {
    Expression::parse(text, names);
  } catch (const ExpressionError& e) {
    if (what) *what = e.what();
    return e.column();
  }
  return 0;
}

TEST(Expression, ErrorsPointAtTheColumn) {
  const std::vector<std::string> s = {"l_s", "d", "theta"};
  std::string what;
  EXPECT_EQ(errorColumn("l_s + * d", s), 7);
  EXPECT_EQ(errorColumn("l_s + thetaa", s, &what), 7);
  EXPECT_NE(what.find("unknown name 'thetaa'"), std::string::npos) << what;
  EXPECT_NE(what.find("l_s, d, theta"), std::string::npos) << what;
  EXPECT_EQ(errorColumn("sqrt(d", s, &what), 7);
  EXPECT_NE(what.find("expected ')'"), std::string::npos) << what;
  EXPECT_EQ(errorColumn("(d + 1", s), 7);
  EXPECT_EQ(errorColumn("2d", s, &what), 2);
  EXPECT_NE(what.find("2*x"), std::string::npos) << what;
  EXPECT_EQ(errorColumn("sqr(d)", s, &what), 1);
  EXPECT_NE(what.find("unknown function 'sqr'"), std::string::npos) << what;
  EXPECT_EQ(errorColumn("atan2(d)", s), 8);
  EXPECT_EQ(errorColumn("d ) ", s), 3);
  EXPECT_EQ(errorColumn("d # 2", s), 3);
  EXPECT_EQ(errorColumn("   ", s), 4);
  EXPECT_EQ(errorColumn("d +", s), 4);
  EXPECT_EQ(errorColumn("d*0x10", s), 4);      // no hex: '0' runs into 'x'
  EXPECT_EQ(errorColumn("d*1e999", s, &what), 3);
  EXPECT_NE(what.find("out of range"), std::string::npos) << what;
  EXPECT_EQ(errorColumn("d*1e", s, &what), 4);
  EXPECT_NE(what.find("exponent"), std::string::npos) << what;
  EXPECT_EQ(errorColumn("1.2.3", s), 4);
  EXPECT_EQ(errorColumn("d + \xC2\xB5", s, &what), 5);
  EXPECT_NE(what.find("'\xC2\xB5'"), std::string::npos) << what;  // the whole character
  // Bounded depth and length: an error, not a stack overflow.
  EXPECT_GT(errorColumn(std::string(30000, '(') + "d" + std::string(30000, ')'), s, &what), 0);
  EXPECT_NE(what.find("nested too deeply"), std::string::npos) << what;
  EXPECT_GT(errorColumn(std::string(50000, '-') + "d", s), 0);
  std::string chain = "d";
  for (int i = 0; i < 20000; ++i) chain += "+d";
  EXPECT_GT(errorColumn(chain, s, &what), 0);
  EXPECT_NE(what.find("too long"), std::string::npos) << what;
}

TEST(Expression, UndefinedAtTheEstimateIsRefusedByTheGuf) {
  Problem pr;
  pr.output = "y";
  pr.inputs = {Input::normal("x", 0, 1)};
  const auto e = Expression::parse("sqrt(x)", {"x"});
  std::vector<double> g(1);
  const double x = 0;
  const double y = e.gradient(&x, g);
  EXPECT_THROW(gufFromGradient(pr, y, g), GeometryError);
}

}  // namespace
}  // namespace probeloop::uncertainty
