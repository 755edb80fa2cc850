// A measured feature's geometry as CMM software reports it: the least-squares element of its
// points (plane, sphere, cylinder; algorithm LEASTSQUARES), started at the nominal, oriented like the nominal (a plane's
// normal outward, a cylinder's axis the nominal's way), its form the range of the residuals; a
// cylinder probed in one section gets its circle's centre, normal and diameter. Points that fix
// no element (too few, degenerate) leave the feature without measured geometry: said by the
// return value, never a NaN.
#pragma once
#include "interop/cmm_document.hpp"

namespace probeloop::interop {

bool fitMeasuredGeometry(CmmFeature& f);

}  // namespace probeloop::interop
