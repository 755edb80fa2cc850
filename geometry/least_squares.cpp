#include "geometry/least_squares.hpp"

#include "core/error.hpp"

namespace probeloop::geometry {

// SKELETON (being implemented): keeps the tree linking while the suite is written.
FitResult fitLeastSquares(ElementKind kind, const Points3&, const LeastSquaresOptions&) {
  throw GeometryError("least-squares " + std::string(elementName(kind)) + " not implemented yet");
}

}  // namespace probeloop::geometry
