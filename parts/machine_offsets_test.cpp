// The offset frame read from a machine description gives, on seed 004's NMV 5000 as a B/C
// trunnion (parts/machines/nmv5000.yaml: B' through the C axis at the table surface, the
// errors' pivot at a sphere centre 75 mm above it), the offsets the machine's own chain gives
// (parts/machine_chain.hpp, geometry/chain_offsets.hpp) at any B and C.
#include "parts/machine_offsets.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "geometry/chain_offsets.hpp"
#include "parts/machine_chain.hpp"

namespace probeloop::parts {
namespace {

TEST(MachineOffsets, OnTheNmv5000TheyAreTheChainsAtEveryB) {
  const auto m = loadMachine(std::string(PROBELOOP_SOURCE_DIR) + "/parts/machines/nmv5000.yaml");
  const double pivot_z = 75, half_d = 160;
  const auto chain = machineChain(m, pivot_z, true);
  const MachineOffsetFrame f = machineOffsetFrame(m, pivot_z, half_d);
  ASSERT_TRUE(f.b_located);
  EXPECT_EQ(f.frame.b_sense, -1.0);  // B' (clockwise seen from +Y unless stated)
  for (double b : {-180.0, -90.0, -20.0, 0.0, 35.0, 90.0, 160.0})
    for (double c : {0.0, 90.0, 217.0}) {
      geometry::ChainState pose;
      pose.positions = {{"X", 120}, {"Y", -60}, {"Z", 230}, {"B", b}, {"C", c}};
      const auto J = geometry::seed004OffsetSensitivity(chain, pose, half_d);
      for (int k = 0; k < 7; ++k) {
        std::array<double, 7> v{};
        v[static_cast<std::size_t>(k)] = 1;
        const auto o = f.offsetsAt(geometry::LocationErrors::fromValues(v), Eigen::Vector3d(120, -60, 230), b);
        EXPECT_LT((J.col(k) - Eigen::Vector3d(o.x_um, o.y_um, o.z_um)).norm(), 1e-7) << "B " << b << " C " << c << " error " << k;
      }
    }
}

TEST(MachineOffsets, WithoutTheBLineOnlyBZero) {
  auto m = loadMachine(std::string(PROBELOOP_SOURCE_DIR) + "/parts/machines/nmv5000.yaml");
  m.b_axis_centre_xz_mm.reset();
  const MachineOffsetFrame f = machineOffsetFrame(m, 75, 160);
  geometry::LocationErrors e;
  e.EB0C_urad = 10;
  EXPECT_NO_THROW(f.offsetsAt(e, Eigen::Vector3d(1, 2, 3), 0));
  EXPECT_THROW(f.offsetsAt(e, Eigen::Vector3d(1, 2, 3), 30), InputError);
}

}  // namespace
}  // namespace probeloop::parts
