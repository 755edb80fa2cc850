// Feature actuals (the CSV a CMM report turns into, docs/formats.md#feature-actuals-csv) against
// both plans that read them: the sphere artifact's centres, and the thermal test piece's
// features route (matched by id or nominal geometry, the plan's points placed on them, the
// whole evaluation); and the same bytes as a QIF or DMIS file of features only.
#include <cstddef>
#include <cstdint>

#include "evaluate/feature_actuals.hpp"
#include "evaluate/thermal_test_piece.hpp"
#include "fuzz/fixtures.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  const std::string text = fuzz::text(data, size);
  fuzz::expectRefusalOrSuccess([&] {
    const auto& m = fuzz::sphereManifest();
    evaluate::sphereCentresFromFeatures(evaluate::parseFeatureActuals(text, "features.csv", m.cycles), m);
  });
  fuzz::expectRefusalOrSuccess([&] {
    evaluate::evaluateThermalTestPieceFromFeatures(fuzz::ttpManifest(), evaluate::parseFeatureActuals(text, "features.csv"),
                                                   "features.csv", "features");
  });
  // The same bytes as a QIF or DMIS file of features only (readStatedFeatures decides).
  return fuzz::expectRefusalOrSuccess([&] {
    if (const auto s = evaluate::readStatedFeatures("features.qif", text, false))
      evaluate::evaluateThermalTestPieceFromFeatures(fuzz::ttpManifest(), s->rows, "features.qif", s->format);
  });
}
