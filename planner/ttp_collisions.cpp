// The thermal test piece's collision rules (docs/thermal-test-piece.md §5): the part's 2D
// geometry, the envelope of what stands on the table and the check of every motion.
#include "planner/ttp_detail.hpp"

#include <algorithm>
#include <cmath>
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"

namespace probeloop::planner::ttp {

namespace {

// Sutherland-Hodgman: the part of convex polygon P with n . p <= d.
Poly clip(const Poly& P, const Vector2d& n, double d) {
  Poly out;
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Vector2d& a = P[i];
    const Vector2d& b = P[(i + 1) % P.size()];
    const double fa = n.dot(a) - d, fb = n.dot(b) - d;
    if (fa <= 0) out.push_back(a);
    if ((fa < 0 && fb > 0) || (fa > 0 && fb < 0)) out.push_back(a + (b - a) * (fa / (fa - fb)));
  }
  return out;
}

double cross(const Vector2d& a, const Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

bool segmentsCross(const Vector2d& a, const Vector2d& b, const Vector2d& c, const Vector2d& d) {
  const double d1 = cross(b - a, c - a), d2 = cross(b - a, d - a), d3 = cross(d - c, a - c), d4 = cross(d - c, b - c);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0));
}

bool insideConvex(const Poly& P, const Vector2d& p) {
  // Counterclockwise polygon: inside = left of every edge.
  for (std::size_t i = 0; i < P.size(); ++i)
    if (cross(P[(i + 1) % P.size()] - P[i], p - P[i]) < 0) return false;
  return true;
}

double segmentPolygon(const Vector2d& a, const Vector2d& b, const Poly& P) {
  if (P.size() < 3) return INFINITY;
  if (insideConvex(P, a) || insideConvex(P, b)) return 0;
  double d = INFINITY;
  for (std::size_t i = 0; i < P.size(); ++i) {
    const Vector2d& c = P[i];
    const Vector2d& e = P[(i + 1) % P.size()];
    if (segmentsCross(a, b, c, e)) return 0;
    d = std::min({d, pointSegment(a, c, e), pointSegment(b, c, e), pointSegment(c, a, b), pointSegment(e, a, b)});
  }
  return d;
}

}  // namespace

double pointSegment(const Vector2d& p, const Vector2d& a, const Vector2d& b) {
  const Vector2d ab = b - a;
  const double L2 = ab.squaredNorm();
  const double s = L2 > 0 ? std::clamp((p - a).dot(ab) / L2, 0.0, 1.0) : 0.0;
  return (p - (a + s * ab)).norm();
}

double segmentOrigin(const Vector2d& a, const Vector2d& b) { return pointSegment(Vector2d::Zero(), a, b); }

Envelope::Envelope(const ThermalTestPiece& t) {
  R = t.blank_diameter_mm / 2;
  H = t.finishedHeight();
  blank_top = t.face_depth_mm;
  floor = t.notchFloorZ();
  fixture_r = std::max(t.adapter_diameter_mm / 2, (t.bolt_circle_diameter_mm + t.washer_diameter_mm) / 2);
  // A 360-gon around the blank's circle, clipped by the notches and the facets.
  Poly circle;
  const double rc = R / std::cos(kPi / 360);
  for (int i = 0; i < 360; ++i) circle.emplace_back(rc * std::cos(degToRad(i + 0.5)), rc * std::sin(degToRad(i + 0.5)));
  const FacetSide sides[4] = {FacetSide::X1, FacetSide::Y1, FacetSide::X2, FacetSide::Y2};
  const double sx[4] = {1, -1, -1, 1}, sy[4] = {1, 1, -1, -1};
  for (int s = 0; s < 4; ++s) {
    Poly P = clip(circle, Vector2d(0, -sy[s]), -t.x_notch_width_mm / 2);
    P = clip(P, Vector2d(-sx[s], 0), -t.y_notch_width_mm / 2);
    for (int k = 1; k <= t.facets_per_segment; ++k) {
      const double a = degToRad(parts::facetNormalAngle(t, sides[s], k));
      P = clip(P, Vector2d(std::cos(a), std::sin(a)), t.facet_apothem_mm + t.facet_allowance_mm);
    }
    for (const auto& v : P) segments_r = std::max(segments_r, v.norm());
    segments.push_back(P);
  }
}

std::string xyz(const Vector3d& v) {
  return "X" + formatNumber(v.x(), 3) + " Y" + formatNumber(v.y(), 3) + " Z" + formatNumber(v.z(), 3);
}

void Collisions::check(const Motion& mo, bool finished) const {
  const std::string tool = mo.tool.probe ? "probe" : "tool T" + std::to_string(mo.tool.number);
  auto fail = [&](const std::string& m) { throw SafetyError(*mo.program + ": " + mo.note->where + ": " + m); };
  const Vector3d qa = mo.from_tip - O, qb = mo.to_tip - O;
  if (!qa.allFinite() || !qb.allFinite() || !std::isfinite(mo.from_c) || !std::isfinite(mo.to_c))
    fail(std::string(mo.what) + " to a position that is not a finite number");
  const double rho = mo.tool.radius_mm;
  const double below = mo.tool.probe ? rho : 0.0;  // lowest point of the tool under its tip coordinate
  const double top = env.top(finished);
  // Below the top a G0 moves one axis at a time: a G0 of several axes may dog-leg (Fanuc
  // non-linear positioning), so such moves are G1 (docs §5).
  if (mo.kind == MotionKind::Rapid && std::min(qa.z(), qb.z()) - below < top - 1e-9) {
    int axes = 0;
    // (1 um: a retract starts at the unrounded contact, its target is rounded to 0.1 um.)
    for (int i = 0; i < 3; ++i) axes += std::fabs(qa(i) - qb(i)) > 1e-3;
    if (axes > 1)
      fail("G0 from " + xyz(mo.from_tip) + " to " + xyz(mo.to_tip) + " moves " + std::to_string(axes) +
           " axes with the " + tool + " below the top of the part (a G0 may dog-leg: only G1 there)");
  }
  // Cuts and measuring moves are meant to touch the part; a retract leaves a contact straight
  // back along the approach line, which the protected move came down clear of.
  if (mo.note->cut || mo.note->retract || mo.kind == MotionKind::Measuring) return;
  if (mo.kind == MotionKind::CIndex || mo.kind == MotionKind::CFeed) {
    if (mo.from_c == mo.to_c) return;
    const double zb = qa.z() - below;
    if (zb >= top - 1e-9) return;
    const double r = qa.head<2>().norm();
    double need = finished && zb >= env.floor - 1e-9 ? env.segments_r + rho : env.R + rho;
    if (zb < -env.H - 1e-9) need = std::max(need, env.fixture_r + rho);
    if (r < need - 1e-9)
      fail(std::string(mo.what) + " turns C from " + formatNumber(mo.from_c, 3) + " to " + formatNumber(mo.to_c, 3) +
           " deg with the " + tool + " at " + xyz(mo.from_tip) + ", " + formatNumber(r, 3) +
           " mm from the C axis: inside the circle the part sweeps (needs " + formatNumber(need, 3) + " mm, or the " + tool +
           " above the part)");
    return;
  }
  // Straight up: the part only narrows upward (bands step in, notches and facets open
  // upward), so a tool rising from where it stands meets nothing.
  if ((qa.head<2>() - qb.head<2>()).norm() < 1e-9 && qb.z() >= qa.z()) return;
  const double zb = std::min(qa.z(), qb.z()) - below;
  if (zb >= top - 1e-9) return;
  const Vector2d pa = parts::unturnedByTable(qa.head<2>(), mo.from_c, cw),
                 pb = parts::unturnedByTable(qb.head<2>(), mo.from_c, cw);  // part frame
  const double d_axis = segmentOrigin(pa, pb);
  double need = env.R + rho;
  if (zb < -env.H - 1e-9) need = std::max(need, env.fixture_r + rho);
  if (d_axis >= need - 1e-9) return;
  double d_part = 0;
  if (finished && zb >= env.floor - 1e-9) {
    d_part = INFINITY;
    for (const auto& s : env.segments) d_part = std::min(d_part, segmentPolygon(pa, pb, s));
    if (d_part >= rho - 1e-9) return;
  }
  fail(std::string(mo.what) + " from " + xyz(mo.from_tip) + " to " + xyz(mo.to_tip) + " at C " + formatNumber(mo.from_c, 3) +
       " would take the " + tool + " through the part: it comes " + formatNumber(d_axis, 3) +
       " mm near the C axis below the top (needs " + formatNumber(need, 3) + " mm outside the blank" +
       (finished ? ", or " + formatNumber(rho, 3) + " mm clear of the segments above the notch floor" : "") + ")");
}

}  // namespace probeloop::planner::ttp
