// The thermal test piece's datum frame (seed 004 L2055; contract in thermal_test_piece.hpp,
// docs/thermal-test-piece-evaluation.md): the datum planes TOP, FLANK_P, FLANK_N and the circle
// CYL -> the part frame, the alignment report, and the frame's sensitivities to every datum
// point for the budgets.
#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "evaluate/ttp_detail.hpp"
#include "geometry/least_squares.hpp"
#include "geometry/minimum_zone.hpp"

namespace probeloop::evaluate {

namespace ttp {

namespace {

// Central-difference step of the datum construction (mm): the frame is smooth in the points,
// second-order terms at 1 um are ~1e-8 relative.
constexpr double kFrameStepMm = 1e-3;

std::vector<Vector3d>& datumSet(DatumSets& d, const std::string& id) {
  if (id == "TOP") return d.top;
  if (id == "FLANK_P") return d.flank_p;
  if (id == "FLANK_N") return d.flank_n;
  return d.cyl;
}

Vector3d centroid(const std::vector<Vector3d>& v) {
  Vector3d s = Vector3d::Zero();
  for (const auto& p : v) s += p;
  return s / static_cast<double>(v.size());
}

geometry::FitResult fitDatum(const std::string& id, geometry::ElementKind kind, const geometry::Points3& pts) {
  try {
    return geometry::fitLeastSquares(kind, pts);
  } catch (const GeometryError& e) {
    throw DatumFailure(id, e.what());
  }
}

// Frame change (delta O, omega) in part coordinates between two frames: new part coordinates
// p'' = M (p' - dO) with M = R' R^T ~ I - [omega]x.
Vector6d frameDelta(const TtpFrame& a, const TtpFrame& b) {
  Vector6d xi;
  xi.head<3>() = a.R * (b.origin_mm - a.origin_mm);
  const Matrix3d M = b.R * a.R.transpose();
  xi(3) = (M(1, 2) - M(2, 1)) / 2;
  xi(4) = (M(2, 0) - M(0, 2)) / 2;
  xi(5) = (M(0, 1) - M(1, 0)) / 2;
  return xi;
}

}  // namespace

// seed 004 L2055: TOP -> z and its origin; the flanks' symmetry -> x direction; the LS circle
// of CYL -> the x/y origin.
FrameFits buildFrame(const DatumSets& d) {
  FrameFits f;
  f.top = fitDatum("TOP", geometry::ElementKind::Plane, d.top);
  f.flank_p = fitDatum("FLANK_P", geometry::ElementKind::Plane, d.flank_p);
  f.flank_n = fitDatum("FLANK_N", geometry::ElementKind::Plane, d.flank_n);
  Vector3d z = f.top.element.direction.normalized();
  // Up: the flanks and the datum band lie below the top face.
  std::vector<Vector3d> below = d.flank_p;
  below.insert(below.end(), d.flank_n.begin(), d.flank_n.end());
  below.insert(below.end(), d.cyl.begin(), d.cyl.end());
  if ((centroid(below) - f.top.element.position_mm).dot(z) > 0) z = -z;
  // Each flank's outward normal points into the notch, toward the other flank.
  Vector3d np = f.flank_p.element.direction.normalized(), nn = f.flank_n.element.direction.normalized();
  if ((centroid(d.flank_n) - f.flank_p.element.position_mm).dot(np) < 0) np = -np;
  if ((centroid(d.flank_p) - f.flank_n.element.position_mm).dot(nn) < 0) nn = -nn;
  Vector3d y = nn - np;
  y -= y.dot(z) * z;
  if (!(y.norm() > 1e-9))
    throw GeometryError("the flanks FLANK_P and FLANK_N are parallel to the top plane: no X direction");
  y.normalize();
  const Vector3d x = y.cross(z);
  const Vector3d p0 = f.top.element.position_mm;
  geometry::Points3 q;
  for (const auto& p : d.cyl) q.emplace_back((p - p0).dot(x), (p - p0).dot(y), 0.0);
  f.cyl = fitDatum("CYL", geometry::ElementKind::Circle2D, q);
  f.frame.origin_mm = p0 + f.cyl.element.position_mm.x() * x + f.cyl.element.position_mm.y() * y;
  f.frame.R.row(0) = x.transpose();
  f.frame.R.row(1) = y.transpose();
  f.frame.R.row(2) = z.transpose();
  return f;
}

DatumFits fitDatums(const std::string& file, const std::vector<Pt>& pts, const PointsByFeature& by) {
  DatumFits out;
  DatumSets& ds = out.sets;
  // A std::map: the datums are checked in the order CYL, FLANK_N, FLANK_P, TOP.
  std::map<std::string, std::vector<Vector3d>*> datum_of{{"TOP", &ds.top}, {"FLANK_P", &ds.flank_p}, {"FLANK_N", &ds.flank_n}, {"CYL", &ds.cyl}};
  const std::map<std::string, std::string> needs{{"TOP", ">= 3 non-collinear points on the top face"},
                                                 {"FLANK_P", ">= 3 non-collinear points on the flank"},
                                                 {"FLANK_N", ">= 3 non-collinear points on the flank"},
                                                 {"CYL", ">= 3 points around the datum band"}};
  for (const auto& [id, set] : datum_of) {
    const auto it = by.find(id);
    if (it == by.end() || it->second.size() < 3)
      featureError(file, pts, it == by.end() ? std::vector<int>{} : it->second, id,
                   "the datum " + id + " needs " + needs.at(id) + " (seed 004 L2055: the part frame)");
    for (int i : it->second) set->push_back(pts[static_cast<std::size_t>(i)].file_mm);
  }
  FrameFits& ff = out.fits;
  try {
    ff = buildFrame(ds);
  } catch (const DatumFailure& x) {
    featureError(file, pts, by.at(x.id), x.id, "the datum " + x.id + " does not define its element: " + x.what());
  } catch (const GeometryError& x) {
    throw InputError(file, 0, std::string("datum frame (TOP, FLANK_P, FLANK_N, CYL): ") + x.what());
  }
  return out;
}

TtpAlignment alignmentReport(const DatumSets& ds, const FrameFits& ff, bool form_mz) {
  const TtpFrame& frame = ff.frame;
  TtpAlignment a;
  a.frame = frame;
  const Eigen::AngleAxisd aa(frame.R);
  a.rotation_urad = aa.axis() * aa.angle() * 1e6;
  a.translation_um = -(frame.R * frame.origin_mm) * 1e3;
  auto form = [&](const std::vector<Vector3d>& v, geometry::ElementKind kind, const geometry::FitResult& ls) {
    if (!form_mz) return ls.form_mm * 1e3;
    try {
      return geometry::fitMinimumZone(kind, v).form_mm * 1e3;
    } catch (const GeometryError&) {
      return ls.form_mm * 1e3;
    }
  };
  geometry::Points3 q;
  for (const auto& p : ds.cyl) {
    const Vector3d r = frame.toPart(p);
    q.emplace_back(r.x(), r.y(), 0.0);
  }
  a.datums.push_back({"TOP", static_cast<int>(ds.top.size()), form(ds.top, geometry::ElementKind::Plane, ff.top)});
  a.datums.push_back({"FLANK_P", static_cast<int>(ds.flank_p.size()), form(ds.flank_p, geometry::ElementKind::Plane, ff.flank_p)});
  a.datums.push_back({"FLANK_N", static_cast<int>(ds.flank_n.size()), form(ds.flank_n, geometry::ElementKind::Plane, ff.flank_n)});
  a.datums.push_back({"CYL", static_cast<int>(ds.cyl.size()), form(q, geometry::ElementKind::Circle2D, ff.cyl)});
  return a;
}

std::vector<std::pair<int, Vector6d>> datumSensitivities(const DatumSets& ds, const FrameFits& ff, const PointsByFeature& by) {
  const TtpFrame& frame = ff.frame;
  std::vector<std::pair<int, Vector6d>> datum_sens;
  // The same order as the datum checks in fitDatums (a std::map: CYL, FLANK_N, FLANK_P, TOP):
  // the budgets sum over these sensitivities in this order.
  const std::map<std::string, const std::vector<Vector3d>*> datum_of{
      {"TOP", &ds.top}, {"FLANK_P", &ds.flank_p}, {"FLANK_N", &ds.flank_n}, {"CYL", &ds.cyl}};
  const Vector3d z_file = frame.R.row(2).transpose();
  for (const auto& [id, set] : datum_of) {
    const auto& idx = by.at(id);
    for (std::size_t j = 0; j < idx.size(); ++j) {
      // Each datum point displaced along its surface normal (the sign is immaterial).
      Vector3d dir;
      if (id == "TOP") {
        dir = z_file;
      } else if (id == "FLANK_P") {
        dir = ff.flank_p.element.direction;
      } else if (id == "FLANK_N") {
        dir = ff.flank_n.element.direction;
      } else {
        const Vector3d r = frame.toPart((*set)[j]);
        dir = frame.R.transpose() * Vector3d(r.x(), r.y(), 0.0).normalized();
      }
      DatumSets plus = ds, minus = ds;
      datumSet(plus, id)[j] += kFrameStepMm * dir;
      datumSet(minus, id)[j] -= kFrameStepMm * dir;
      const auto fp = buildFrame(plus).frame, fm = buildFrame(minus).frame;
      datum_sens.push_back({idx[j], (frameDelta(frame, fp) - frameDelta(frame, fm)) / (2 * kFrameStepMm)});
    }
  }
  return datum_sens;
}

}  // namespace ttp

TtpFrame ttpDatumFrame(const TtpPoints& points) {
  using ttp::buildFrame;
  using ttp::DatumFailure;
  using ttp::DatumSets;
  DatumSets ds;
  for (const auto& p : points.points) {
    if (p.feature == "TOP") ds.top.push_back(p.p_mm);
    if (p.feature == "FLANK_P") ds.flank_p.push_back(p.p_mm);
    if (p.feature == "FLANK_N") ds.flank_n.push_back(p.p_mm);
    if (p.feature == "CYL") ds.cyl.push_back(p.p_mm);
  }
  for (const auto& [id, v] : std::map<std::string, std::size_t>{{"TOP", ds.top.size()}, {"FLANK_P", ds.flank_p.size()},
                                                                {"FLANK_N", ds.flank_n.size()}, {"CYL", ds.cyl.size()}})
    if (v < 3)
      throw InputError(points.file, 0, "the datum " + id + " has " + std::to_string(v) + " points; it needs >= 3 (seed 004 L2055)");
  try {
    return buildFrame(ds).frame;
  } catch (const DatumFailure& x) {
    throw InputError(points.file, 0, "the datum " + x.id + " does not define its element: " + x.what());
  } catch (const GeometryError& x) {
    throw InputError(points.file, 0, std::string("datum frame: ") + x.what());
  }
}

}  // namespace probeloop::evaluate
