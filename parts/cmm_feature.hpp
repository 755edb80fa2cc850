// A nominal feature of a test piece as a CMM exchange document's feature (interop/): its kind,
// its nominal geometry (a plane's point and outward normal, a cylinder's axis point, axis and
// diameter, a sphere's centre and diameter) and, from the planned points' outward normals,
// whether a cylinder is a bore (normals towards the axis). Points are the caller's.
// Contract: a kind QIF is not written for is a logic_error (the test-piece loaders make none).
#pragma once
#include "interop/cmm_document.hpp"
#include "parts/feature.hpp"

namespace probeloop::parts {

interop::CmmFeature cmmFeatureOf(const NominalFeature& n);
// After the points are in: a cylinder whose first point's outward normal points to the axis
// is internal.
void setInternalFromPoints(interop::CmmFeature& f);

}  // namespace probeloop::parts
