#include "geometry/reference_data.hpp"

#include "core/error.hpp"

namespace probeloop::geometry {

// SKELETON (being implemented): keeps the tree linking while the suite is written.
std::vector<ReferenceDataSet> referenceSuite(std::uint64_t) {
  throw GeometryError("reference suite not implemented yet");
}
ReferenceDataSet makeReferenceData(const Element&, int, double, double, double, std::uint64_t) {
  throw GeometryError("reference data not implemented yet");
}

}  // namespace probeloop::geometry
