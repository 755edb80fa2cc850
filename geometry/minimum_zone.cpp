#include "geometry/minimum_zone.hpp"

#include "core/error.hpp"

namespace probeloop::geometry {

// SKELETON (being implemented): keeps the tree linking while the suite is written.
FitResult fitMinimumZone(ElementKind kind, const Points3&) {
  throw GeometryError("minimum zone " + std::string(elementName(kind)) + " not implemented yet");
}
FitResult fitMaximumInscribed(ElementKind kind, const Points3&) {
  throw GeometryError("maximum inscribed " + std::string(elementName(kind)) + " not implemented yet");
}
FitResult fitMinimumCircumscribed(ElementKind kind, const Points3&) {
  throw GeometryError("minimum circumscribed " + std::string(elementName(kind)) + " not implemented yet");
}

}  // namespace probeloop::geometry
