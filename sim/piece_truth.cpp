#include "sim/piece_truth.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/csv.hpp"
#include "core/units.hpp"
#include "geometry/fit.hpp"
#include "geometry/location_errors.hpp"

namespace probeloop::sim {

using Eigen::Vector3d;

namespace {

constexpr double kWindow_mm = 0.5;    // search from this far outside the nominal surface, to as far inside
constexpr double kSameSurface_mm = 0.02;  // farther from the median height: another surface

struct Sample {
  Vector3d p;
  double height;  // along the nominal normal from the nominal surface
  int tag;
};

// One query along -n from window outside q: the surface point, if the line starts in air
// and meets material within the window.
bool sampleAt(const Stock& stock, const Vector3d& q, const Vector3d& n, Sample& out) {
  const Vector3d from = q + kWindow_mm * n;
  const auto hit = stock.firstMaterialHit(from, -n, 2 * kWindow_mm);
  if (!hit || !(hit->s > 0)) return false;
  out = {from - hit->s * n, kWindow_mm - hit->s, hit->tag};
  return true;
}

// Keep the samples of the feature's own surface: within kSameSurface of the median height
// (the engraved mark is 0.2 mm deep, the notch floors 0.1 mm and more apart).
std::vector<Sample> sameSurface(std::vector<Sample> s) {
  if (s.empty()) return s;
  std::vector<double> h;
  for (const auto& x : s) h.push_back(x.height);
  std::nth_element(h.begin(), h.begin() + static_cast<long>(h.size() / 2), h.end());
  const double median = h[h.size() / 2];
  std::vector<Sample> out;
  for (const auto& x : s)
    if (std::fabs(x.height - median) <= kSameSurface_mm) out.push_back(x);
  return out;
}

int majorityTag(const std::vector<Sample>& s) {
  std::map<int, int> count;
  for (const auto& x : s) ++count[x.tag];
  int best = -1, n = -1;
  for (const auto& [tag, c] : count)
    if (c > n) best = tag, n = c;
  return best;
}

AsCutFeature asCut(const parts::NominalFeature& f, const Stock& stock) {
  AsCutFeature a;
  a.id = f.id;
  a.kind = f.kind;
  a.role = f.role;
  std::vector<Sample> samples;
  Sample s;
  if (f.kind == "plane") {
    const Vector3d n = f.direction.normalized(), u = f.u.normalized(), v = n.cross(u);
    const int nu = std::max(5, static_cast<int>(std::ceil(1.6 * f.half_u_mm / 10.0)) + 1);
    const int nv = std::max(3, static_cast<int>(std::ceil(1.6 * f.half_v_mm / 10.0)) + 1);
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        const double ou = 0.8 * f.half_u_mm * (-1.0 + 2.0 * i / (nu - 1));
        const double ov = 0.8 * f.half_v_mm * (-1.0 + 2.0 * j / (nv - 1));
        if (sampleAt(stock, f.point_mm + ou * u + ov * v, n, s)) samples.push_back(s);
      }
  } else if (f.kind == "cylinder") {
    const Vector3d axis = f.direction.normalized();
    const Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
    for (int k = 0; k < 36; ++k) {
      const double th = 2 * kPi * k / 36;
      const Vector3d n = std::cos(th) * e1 + std::sin(th) * e2;
      if (sampleAt(stock, f.point_mm + f.radius_mm * n, n, s)) samples.push_back(s);
    }
  } else {
    a.why = "kind " + f.kind + " is not sampled";
    return a;
  }
  samples = sameSurface(std::move(samples));
  // A floor around a boss (the stepped workpiece's rings, 7.5 mm wide) is mostly covered by
  // the boss above it, which a 10 mm grid can miss: resample every 2 mm over its extent.
  if (f.kind == "plane" && samples.size() < 6) {
    samples.clear();
    const Vector3d n = f.direction.normalized(), u = f.u.normalized(), v = n.cross(u);
    const int nu = static_cast<int>(std::floor(1.9 * f.half_u_mm / 2.0)) + 1;
    const int nv = static_cast<int>(std::floor(1.9 * f.half_v_mm / 2.0)) + 1;
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        const double ou = -0.95 * f.half_u_mm + 2.0 * i, ov = -0.95 * f.half_v_mm + 2.0 * j;
        if (sampleAt(stock, f.point_mm + ou * u + ov * v, n, s)) samples.push_back(s);
      }
    samples = sameSurface(std::move(samples));
  }
  a.points = static_cast<int>(samples.size());
  if (a.points < 3) {
    a.why = "fewer than 3 points of the surface within " + formatNumber(kWindow_mm) +
            " mm of the nominal " + f.kind;
    return a;
  }
  geometry::Points3 pts;
  for (const auto& x : samples) pts.push_back(x.p);
  a.cut = majorityTag(samples);
  try {
    if (f.kind == "plane") {
      const auto fit = geometry::fitElement(geometry::ElementKind::Plane, pts, {});
      a.point_mm = fit.fit.element.position_mm;
      a.normal = fit.fit.element.direction;
      if (a.normal.dot(f.direction) < 0) a.normal = -a.normal;  // outward, as the nominal
    } else {
      // The points lie in the plane of the cylinder's mid height (horizontal for the datum
      // band): a circle in XY.
      const auto fit = geometry::fitElement(geometry::ElementKind::Circle2D, pts, {});
      a.point_mm = Vector3d(fit.fit.element.position_mm.x(), fit.fit.element.position_mm.y(), f.point_mm.z());
      a.normal = f.direction.normalized();
      a.radius_mm = fit.fit.element.radius_mm;
    }
  } catch (const std::exception& e) {
    a.why = std::string("fit failed: ") + e.what();
    return a;
  }
  a.found = true;
  return a;
}

const AsCutFeature* byId(const std::vector<AsCutFeature>& v, const std::string& id) {
  for (const auto& f : v)
    if (f.id == id) return &f;
  return nullptr;
}

}  // namespace

TestPieceTruth testPieceTruth(const parts::TestPiece& piece, const Stock& stock, const std::vector<CutState>& cuts) {
  TestPieceTruth t;
  t.cuts = cuts;
  for (const auto& f : piece.features) t.features.push_back(asCut(f, stock));

  // The datum frame (seed 004 L2055).
  const AsCutFeature *top = byId(t.features, "TOP"), *fp = byId(t.features, "FLANK_P"),
                     *fn = byId(t.features, "FLANK_N"), *cyl = byId(t.features, "CYL");
  for (const auto* f : {top, fp, fn, cyl})
    if (!f || !f->found) t.datum.why += std::string(t.datum.why.empty() ? "" : "; ") + "datum feature " +
                                        (f ? f->id + " not found: " + f->why : std::string("missing"));
  if (t.datum.why.empty()) {
    DatumFrame& d = t.datum;
    d.z = top->normal;
    d.origin_mm = cyl->point_mm - d.z * d.z.dot(cyl->point_mm - top->point_mm);
    Vector3d y = fn->normal - fp->normal;
    y -= y.dot(d.z) * d.z;
    if (y.norm() < 1e-9) {
      d.why = "the flanks' normals give no direction across the notch";
    } else {
      d.y = y.normalized();
      d.x = d.y.cross(d.z);
      d.found = true;
    }
  }
  if (t.datum.found) {
    const DatumFrame& d = t.datum;
    for (auto& f : t.features) {
      if (!f.found) continue;
      if (f.role == "facet") {
        f.d_mm = f.normal.dot(f.point_mm - d.origin_mm);
      } else if (f.role == "z_path") {
        const Vector3d p = f.point_mm - d.origin_mm;
        const Vector3d pd(d.x.dot(p), d.y.dot(p), d.z.dot(p)), nd(d.x.dot(f.normal), d.y.dot(f.normal), d.z.dot(f.normal));
        // The nominal path centre (0, y_j) in the datum frame.
        double y_j = 0;
        for (const auto& nf : piece.features)
          if (nf.id == f.id) y_j = nf.point_mm.y();
        const double z = pd.z() - (nd.x() * (0.0 - pd.x()) + nd.y() * (y_j - pd.y())) / nd.z();
        f.depth_mm = -z;
        f.beta_urad = std::atan2(nd.x(), nd.z()) * 1e6;
      }
    }
  }

  // Cutting cycles (seed 004 Eqs. 7.1-7.5, 7.9 via parts::ttpErrors).
  const auto* ttp = piece.thermalTestPiece();
  if (!ttp) return t;
  const auto cycles = parts::cuttingCycles(*ttp);
  parts::TtpMeasures reference;
  bool have_reference = false;
  for (const auto& c : cycles) {
    TtpCycleTruth ct;
    ct.cycle = c.cycle;
    ct.z_path = c.z_path;
    ct.facet = c.facet;
    const std::string ids[5] = {parts::zPathId(c.z_path), parts::facetId(parts::FacetSide::X1, c.facet),
                                parts::facetId(parts::FacetSide::X2, c.facet), parts::facetId(parts::FacetSide::Y1, c.facet),
                                parts::facetId(parts::FacetSide::Y2, c.facet)};
    const AsCutFeature* f[5];
    double time_sum = 0;
    bool timed = true;
    for (int k = 0; k < 5; ++k) {
      f[k] = byId(t.features, ids[k]);
      if (!f[k] || !f[k]->found) ct.why += (ct.why.empty() ? "" : "; ") + ids[k] + " not found";
      else if (f[k]->cut >= 0 && f[k]->cut < static_cast<int>(cuts.size())) time_sum += cuts[static_cast<std::size_t>(f[k]->cut)].time_s;
      else timed = false;
    }
    if (!t.datum.found) ct.why += (ct.why.empty() ? "" : "; ") + std::string("no datum frame");
    if (ct.why.empty()) {
      ct.measures.d_Z_mm = f[0]->depth_mm;
      ct.measures.beta_urad = f[0]->beta_urad;
      ct.measures.d_X1_mm = f[1]->d_mm;
      ct.measures.d_X2_mm = f[2]->d_mm;
      ct.measures.d_Y1_mm = f[3]->d_mm;
      ct.measures.d_Y2_mm = f[4]->d_mm;
      if (timed) ct.time_s = time_sum / 5;
      if (c.cycle == 0) {
        reference = ct.measures;
        have_reference = true;
      }
      if (have_reference) {
        ct.errors = parts::ttpErrors(ct.measures, reference);
        ct.complete = true;
      } else {
        ct.why = "the reference cycle 0 is incomplete";
      }
    }
    t.cycles.push_back(ct);
  }
  return t;
}

namespace {

nlohmann::ordered_json vec(const Vector3d& v) { return {v.x(), v.y(), v.z()}; }
nlohmann::ordered_json num(double v) { return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(); }

nlohmann::ordered_json featuresJson(const std::vector<AsCutFeature>& fs, const std::vector<CutState>& cuts) {
  const auto& names = geometry::LocationErrors::names();
  nlohmann::ordered_json features = nlohmann::ordered_json::array();
  for (const auto& f : fs) {
    nlohmann::ordered_json j{{"id", f.id}, {"kind", f.kind}, {"role", f.role}, {"points", f.points}};
    if (!f.found) {
      j["as_cut"] = nullptr;
      j["why"] = f.why;
      features.push_back(j);
      continue;
    }
    j["cut_index"] = f.cut;
    const CutState* cs = f.cut >= 0 && f.cut < static_cast<int>(cuts.size()) ? &cuts[static_cast<std::size_t>(f.cut)] : nullptr;
    j["cut_time_s"] = cs ? nlohmann::ordered_json(cs->time_s) : nlohmann::ordered_json();
    nlohmann::ordered_json a;
    if (f.kind == "cylinder") {
      a["centre_mm"] = vec(f.point_mm);
      a["radius_mm"] = f.radius_mm;
    } else {
      a["point_mm"] = vec(f.point_mm);
      a["normal"] = vec(f.normal);
    }
    if (f.role == "facet") a["d_mm"] = num(f.d_mm);
    if (f.role == "z_path") {
      a["depth_mm"] = num(f.depth_mm);
      a["beta_urad"] = num(f.beta_urad);
    }
    j["as_cut"] = a;
    if (cs) {
      nlohmann::ordered_json m{{"time_s", cs->time_s}, {"tool", cs->tool}};
      for (int k = 0; k < 7; ++k) m[names[k]] = cs->location[static_cast<std::size_t>(k)];
      m["tool_um"] = vec(cs->tool_um);
      m["part_above_20C_K"] = cs->part_above_20C_K;
      m["feed_mm_per_min"] = cs->feed_mm_per_min;
      m["spindle_rpm"] = cs->spindle_rpm;
      m["deflection_um"] = vec(cs->deflection_um);
      m["axes_um"] = {vec(cs->axes_start_um), vec(cs->axes_end_um)};
      if (cs->scale_um_per_mm != Eigen::Vector3d::Zero()) m["scale_um_per_mm"] = vec(cs->scale_um_per_mm);
      if (cs->lost_motion_um != Eigen::Vector3d::Zero()) m["lost_motion_um"] = vec(cs->lost_motion_um);
      j["machine"] = m;
    } else {
      j["machine"] = nullptr;
    }
    features.push_back(j);
  }
  return features;
}

}  // namespace

void writeTestPieceTruth(const TestPieceTruth& t, nlohmann::ordered_json& jt) {
  jt["test_piece_note"] =
      "features[].as_cut: the surface as cut, sampled exactly and fitted by least squares (part frame, 20 C, what a "
      "perfect CMM finds); d_mm/depth_mm/beta_urad in datum_frame (seed 004 L2055); machine: the state when the cut "
      "that made it started; ttp_cycles: seed 004 Eqs. 7.1-7.5 (7.1/7.2 sign corrected), ETTP_um = Eq. 7.3, "
      "ETTP_7_9_um = Eq. 7.9, against cycle 0 (docs/simulator.md 3.1)";
  jt["features"] = featuresJson(t.features, t.cuts);
  const auto& d = t.datum;
  if (d.found)
    jt["datum_frame"] = {{"origin_mm", vec(d.origin_mm)}, {"x", vec(d.x)}, {"y", vec(d.y)}, {"z", vec(d.z)}};
  else
    jt["datum_frame"] = {{"why", d.why}};
  nlohmann::ordered_json cycles = nlohmann::ordered_json::array();
  for (const auto& c : t.cycles) {
    nlohmann::ordered_json j{{"cycle", c.cycle}, {"z_path", c.z_path}, {"facet", c.facet}, {"time_s", num(c.time_s)}};
    if (!c.complete) {
      j["why"] = c.why;
      cycles.push_back(j);
      continue;
    }
    const auto& m = c.measures;
    const auto& e = c.errors;
    j["d_X1_mm"] = m.d_X1_mm;
    j["d_X2_mm"] = m.d_X2_mm;
    j["d_Y1_mm"] = m.d_Y1_mm;
    j["d_Y2_mm"] = m.d_Y2_mm;
    j["d_Z_mm"] = m.d_Z_mm;
    j["beta_urad"] = m.beta_urad;
    j["EX_um"] = e.EX_um;
    j["EY_um"] = e.EY_um;
    j["EZ_um"] = e.EZ_um;
    j["EB_urad"] = e.EB_urad;
    j["ETTP_um"] = e.ETTP_7_3_um;
    j["ETTP_7_9_um"] = e.ETTP_7_9_um;
    j["EX_printed_um"] = e.EX_printed_um;
    j["EY_printed_um"] = e.EY_printed_um;
    cycles.push_back(j);
  }
  jt["ttp_cycles"] = cycles;
}

std::vector<AsCutFeature> asCutFeatures(const parts::TestPiece& piece, const Stock& stock) {
  std::vector<AsCutFeature> out;
  for (const auto& f : piece.features) out.push_back(asCut(f, stock));
  return out;
}

void writeAsCutFeatures(const std::vector<AsCutFeature>& features, const std::vector<CutState>& cuts,
                        nlohmann::ordered_json& jt) {
  jt["test_piece_note"] =
      "features[].as_cut: the surface as cut, sampled exactly and fitted by least squares (part frame, 20 C, what a "
      "perfect CMM finds); machine: the state when the cut that made most of it started (tool_um: thermal and static "
      "tool drift; deflection_um: the tool pushed from the material, workpiece frame; axes_um: the linear axes' "
      "geometric error at the cut's start and end); events[].axes_um: the same at each probe contact "
      "(docs/simulator.md 3.2)";
  jt["features"] = featuresJson(features, cuts);
}

}  // namespace probeloop::sim
