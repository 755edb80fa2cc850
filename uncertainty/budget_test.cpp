#include "uncertainty/budget.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace probeloop::uncertainty;

TEST(Budget, QuadratureSortAndExpanded) {
  const auto b = combine("l", "nm", 0, {{"a", 'B', "normal", "", 3}, {"b", 'B', "normal", "", 4}});
  EXPECT_DOUBLE_EQ(b.u_c, 5.0);
  EXPECT_DOUBLE_EQ(b.U, 10.0);
  EXPECT_EQ(b.contributions.front().input, "b");
  EXPECT_TRUE(std::isinf(b.nu_eff));
}

TEST(Budget, WelchSatterthwaiteMatchesGumH1) {
  // JCGM 100 H.1 end gauge, Table H.1: the non-zero contributions u_i(l) (nm) and their
  // dof (alpha_S and theta have zero first-order sensitivity). GUM: u_c = 32 nm,
  // nu_eff = 16.7.
  const auto b = combine("l", "nm", 0,
                         {{"l_S", 'B', "", "", 25, 18},
                          {"d", 'A', "", "", 9.7, 25.6},
                          {"delta_alpha", 'B', "", "", 2.9, 50},
                          {"delta_theta", 'B', "", "", 16.6, 2}});
  EXPECT_NEAR(b.u_c, 32.0, 0.5);     // GUM H.1.6: u_c = 32 nm
  EXPECT_NEAR(b.nu_eff, 16.7, 0.1);  // GUM H.1.6: nu_eff = 16.7 -> 16
}
