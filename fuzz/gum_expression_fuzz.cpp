// The GUM expression parser (uncertainty/expression.hpp): a measurement model as text, parsed
// against a fixed set of input names, then evaluated with its gradient (ceres::Jet) at a point.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz/fuzz_support.hpp"
#include "uncertainty/expression.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static const std::vector<std::string> symbols = {"x", "y", "z", "l_s", "d", "theta", "alpha_s",
                                                   "dalpha", "dtheta", "m_R", "R", "U"};
  static const std::vector<double> at = {0.5, -1.25, 3.0, 50.000623, 2.15e-4, -0.1, 11.5e-6,
                                         1e-6, 0.02, 1e4, 50.0, 1.0};
  const std::string text = fuzz::text(data, size);
  return fuzz::expectRefusalOrSuccess([&] {
    const auto e = uncertainty::Expression::parse(text, symbols);
    std::vector<double> dydx(symbols.size());  // gradient() fills one entry per input: the caller sizes it
    e.gradient(at.data(), dydx);
    e.evaluate<double>(at.data());
  });
}
