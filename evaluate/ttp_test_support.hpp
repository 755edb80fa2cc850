// Test support for the thermal-test-piece evaluation: a plan manifest built by hand from the
// shipped description (parts/: loadThermalTestPiece, nominalFeatures, cuttingCycles; no
// planner), the inspection points of docs/thermal-test-piece.md §3 in the part frame, and
// synthetic measurements of surfaces displaced by chosen amounts. The machine placement is
// written out here (p_machine = c + Rz(s C) (p + origin - c), s = -1 when C+ is clockwise),
// independently of evaluate/ttp_ingest.cpp.
#pragma once
#include <Eigen/Dense>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/csv.hpp"
#include "evaluate/thermal_test_piece.hpp"
#include "core/units.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/piece_kinds.hpp"
#include "parts/thermal_test_piece.hpp"

namespace probeloop::evaluate::ttptest {

using Eigen::Vector3d;

struct PlannedPoint {
  std::string feature;
  int position = 0, point = 0;
  Vector3d surface_mm;  // part frame, nominal
  Vector3d outward;     // part frame
  double c_deg = 0;
};

struct Fixture {
  parts::ThermalTestPiece t;
  parts::PlanManifest m;
  std::vector<PlannedPoint> planned;
};

inline Vector3d rotZ(const Vector3d& v, double deg) {
  const double a = degToRad(deg), c = std::cos(a), s = std::sin(a);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z()};
}

inline double wrap180(double a) {
  a = std::fmod(a, 360.0);
  if (a > 180) a -= 360;
  if (a <= -180) a += 360;
  return a;
}

inline Fixture makeFixture(bool clockwise = true) {
  Fixture f;
  f.t = parts::loadThermalTestPiece(std::string(PROBELOOP_SOURCE_DIR) + "/parts/thermal_test_piece.yaml");
  const auto& t = f.t;
  auto& m = f.m;
  m.file = "hand-built-plan.json";
  m.kind = "thermal_test_piece";
  m.dialect = "fanuc";
  m.machine_name = "test machine";
  m.programs.push_back({"inspection.nc", "fanuc", "dprnt.txt", "inspection", 0, 0});
  m.c_axis_centre_mm = {12.5, -7.25};
  m.c_positive_is_clockwise = clockwise;
  m.table_surface_z_mm = 100;
  m.coordinate_resolution_mm = 0.001;
  m.probe_tool = 20;
  m.tip_radius_mm = 3;
  m.probe_repeatability_2sigma_um = 1;
  m.part_name = t.name;
  m.part_origin_mm = parts::partOriginOnMachine(t, m.c_axis_centre_mm, m.table_surface_z_mm);
  m.material_name = t.material.name;
  m.material_alpha_um_per_m_K = t.material.alpha_um_per_m_K;
  m.ttp.z_paths = t.z_paths;
  m.ttp.facets_per_segment = t.facets_per_segment;
  m.ttp.eq_7_10_alpha_um_per_m_K = t.eq_7_10_alpha_um_per_m_K;
  m.ttp.alpha_u_um_per_m_K = t.alpha_u_um_per_m_K;
  m.ttp.eq_7_10_radius_mm = t.eq_7_10_radius_mm;
  m.ttp.cmm = t.cmm;
  m.ttp.on_machine_repeatability_um = t.on_machine_repeatability_um;
  m.ttp.on_machine_temperature_change_K = t.on_machine_temperature_change_K;
  m.evaluation = parts::thermalTestPieceEvaluation();  // as the planner writes it into the manifest
  const auto cycles = parts::cuttingCycles(t);
  for (const auto& c : cycles) {
    parts::ManifestCycle x;
    x.cycle = c.cycle;
    x.phase = c.phase;
    x.c_axis_rpm_before = c.c_axis_rpm_before;
    x.start_s = c.nominal_time_s;
    x.end_s = c.nominal_time_s + 300;
    x.z_path = c.z_path;
    x.facet = c.facet;
    m.cut_cycles.push_back(x);
  }
  int position = 0;
  const std::map<std::string, double> cut_offset{{"Z", 30}, {"X1", 90}, {"Y1", 150}, {"X2", 210}, {"Y2", 270}};
  for (const auto& n : parts::nominalFeatures(t)) {
    parts::ManifestFeature mf;
    mf.nominal = n;
    if (n.role == "z_path" || n.role == "facet")
      for (const auto& c : cycles)
        if ((n.role == "z_path" ? c.z_path : c.facet) == n.index) {
          mf.cycle = c.cycle;
          mf.cut_time_s = c.nominal_time_s + cut_offset.at(n.group);
        }
    mf.position = ++position;
    m.features.push_back(mf);
  }
  // Inspection points (docs/thermal-test-piece.md §3), part frame surface points.
  const double s = clockwise ? -1.0 : 1.0;
  auto add = [&](const parts::ManifestFeature& mf, const Vector3d& p, const Vector3d& n, double c_deg) {
    PlannedPoint q;
    q.feature = mf.nominal.id;
    q.position = mf.position;
    q.surface_mm = p;
    q.outward = n;
    q.c_deg = c_deg;
    int k = 0;
    for (const auto& x : f.planned)
      if (x.feature == q.feature) ++k;
    q.point = k + 1;
    f.planned.push_back(q);
  };
  const double r_band = t.datum_band_diameter_mm / 2;
  for (const auto& mf : m.features) {
    const auto& n = mf.nominal;
    if (n.id == "TOP") {
      for (double sx : {1.0, -1.0})
        for (double sy : {1.0, -1.0})
          for (const auto& xy : {Eigen::Vector2d(20, 70), Eigen::Vector2d(60, 65), Eigen::Vector2d(30, 88)})
            add(mf, Vector3d(sx * xy.x(), sy * xy.y(), 0), Vector3d::UnitZ(), 0);
    } else if (n.id == "FLANK_P" || n.id == "FLANK_N") {
      for (double x : {-60.0, -20.0, 20.0, 60.0})
        for (double z : {-3.0, -9.0}) add(mf, Vector3d(x, n.point_mm.y(), z), n.direction, 0);
    } else if (n.id == "CYL") {
      for (int k = 0; k < t.datum_circle_points; ++k) {
        const double th = 15.0 + 360.0 * k / t.datum_circle_points;
        add(mf, Vector3d(r_band * std::cos(degToRad(th)), r_band * std::sin(degToRad(th)), t.datum_circle_z_mm),
            Vector3d(std::cos(degToRad(th)), std::sin(degToRad(th)), 0), wrap180(-th / s));
      }
    } else if (n.role == "z_path") {
      for (double x : t.z_path_points_along_mm)
        for (double a : t.z_path_points_across_mm) add(mf, Vector3d(x, n.point_mm.y() + a, n.point_mm.z()), Vector3d::UnitZ(), 0);
    } else if (n.role == "facet") {
      for (double a : t.facet_points_across_mm)
        for (double h : t.facet_points_heights_mm) {
          const Vector3d p = t.facet_apothem_mm * n.direction + a * n.u;
          add(mf, Vector3d(p.x(), p.y(), h), n.direction, wrap180(-n.angle_deg / s));
        }
    }
  }
  for (const auto& q : f.planned) {
    parts::ManifestPoint p;
    p.feature = q.feature;
    p.position = q.position;
    p.point = q.point;
    p.c_deg = q.c_deg;
    // The placement on the machine, written out: p_m = c + Rz(s C)(p + origin - c).
    const Vector3d c3(m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y(), 0);
    const Vector3d surface_m = c3 + rotZ(q.surface_mm + m.part_origin_mm - c3, s * q.c_deg);
    const Vector3d outward_m = rotZ(q.outward, s * q.c_deg);
    p.approach = -outward_m;
    p.contact_mm = surface_m + m.tip_radius_mm * outward_m;
    p.time_in_cycle_s = 0;
    m.points.push_back(p);
  }
  return f;
}

// Displacements of the cut surfaces, by feature id: facets move along their outward normal
// (mm); Z paths are cut deeper by `offset` (mm) and tilted by beta about +Y (a right-hand
// angle, rad): the plane z = z_nom - offset - tan(beta) x, normal ~ (tan beta, 0, 1).
struct Truth {
  std::map<std::string, double> offset_mm, beta_rad;
};

struct Measured {
  std::string feature;
  int position = 0, point = 0;
  Vector3d surface_mm;  // part frame
  double c_deg = 0;
  Vector3d outward;
};

inline std::vector<Measured> measure(const Fixture& f, const Truth& truth) {
  std::vector<Measured> out;
  for (const auto& q : f.planned) {
    Measured x{q.feature, q.position, q.point, q.surface_mm, q.c_deg, q.outward};
    const auto& nom = f.m.feature(q.feature)->nominal;
    const double off = truth.offset_mm.count(q.feature) ? truth.offset_mm.at(q.feature) : 0.0;
    if (nom.role == "facet") {
      x.surface_mm += off * q.outward;
    } else if (nom.role == "z_path") {
      const double b = truth.beta_rad.count(q.feature) ? truth.beta_rad.at(q.feature) : 0.0;
      x.surface_mm.z() = nom.point_mm.z() - off - std::tan(b) * x.surface_mm.x();
    }
    out.push_back(x);
  }
  return out;
}

// A CMM export: optional labels, points moved by p -> Q p + shift.
inline std::string cmmCsv(const std::vector<Measured>& pts, bool labels, const Eigen::Matrix3d& Q = Eigen::Matrix3d::Identity(),
                          const Vector3d& shift = Vector3d::Zero(), const std::string& label_prefix = "") {
  std::ostringstream o;
  o << "# synthetic CMM export\n" << (labels ? "feature,point," : "") << "x_mm,y_mm,z_mm\n";
  for (const auto& p : pts) {
    const Vector3d v = Q * p.surface_mm + shift;
    if (labels) o << label_prefix << p.feature << "," << p.point << ",";
    o << formatNumber(v.x()) << "," << formatNumber(v.y()) << "," << formatNumber(v.z()) << "\n";
  }
  return o.str();
}

// On-machine: tip centres in machine coordinates at each point's C.
inline Vector3d tipCentre(const Fixture& f, const Measured& p) {
  const auto& m = f.m;
  const double s = m.c_positive_is_clockwise ? -1.0 : 1.0;
  const Vector3d c3(m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y(), 0);
  const Vector3d surface_m = c3 + rotZ(p.surface_mm + m.part_origin_mm - c3, s * p.c_deg);
  const Vector3d outward_m = rotZ(p.outward, s * p.c_deg);
  return surface_m + m.tip_radius_mm * outward_m;  // square probing: the tip touches along the normal
}

inline std::string pointsCsv(const Fixture& f, const std::vector<Measured>& pts) {
  std::ostringstream o;
  o << "# synthetic on-machine points\ntime_s,cycle,c_deg,feature,point,x_mm,y_mm,z_mm,nx,ny,nz\n";
  double t = 0;
  for (const auto& p : pts) {
    const Vector3d tip = tipCentre(f, p);
    const double s = f.m.c_positive_is_clockwise ? -1.0 : 1.0;
    const Vector3d a = -rotZ(p.outward, s * p.c_deg);
    o << formatNumber(t += 2, 3) << ",1," << formatNumber(p.c_deg) << ",P" << p.position << "," << p.point << ","
      << formatNumber(tip.x()) << "," << formatNumber(tip.y()) << "," << formatNumber(tip.z()) << "," << formatNumber(a.x()) << ","
      << formatNumber(a.y()) << "," << formatNumber(a.z()) << "\n";
  }
  return o.str();
}

inline std::string dprnt(const Fixture& f, const std::vector<Measured>& pts) {
  std::ostringstream o;
  o << "%\n";
  char buf[160];
  for (const auto& p : pts) {
    const Vector3d tip = tipCentre(f, p);
    std::snprintf(buf, sizeof buf, "PT     1 %d %d %12.6f %12.6f %12.6f\n", p.position, p.point, tip.x(), tip.y(), tip.z());
    o << buf;
  }
  return o.str();
}

inline std::string facetId(const Fixture& f, const std::string& side, int cycle) {
  return side + "_" + std::to_string(f.t.order[static_cast<std::size_t>(cycle)]);
}
inline std::string zId(const Fixture& f, int cycle) { return "Z" + std::to_string(f.t.order[static_cast<std::size_t>(cycle)]); }

inline std::string tempFile(const std::string& name, const std::string& text) {
  static int n = 0;
  const std::string p = std::string(::testing::TempDir()) + "probeloop-ttp-" + std::to_string(n++) + "-" + name;
  std::ofstream(p) << text;
  return p;
}

// --- shared expectations ----------------------------------------------------------------------

// Cycle c's value of quantity q; fails the test when absent.
inline double value(const TtpEvaluation& e, int c, const std::string& q) {
  for (const auto& x : e.cycles)
    if (x.cycle == c) {
      const auto* b = x.value(q);
      if (!b) ADD_FAILURE() << "cycle " << c << " has no " << q;
      return b ? b->value : NAN;
    }
  ADD_FAILURE() << "no cycle " << c;
  return NAN;
}
inline const uncertainty::Budget& budget(const TtpEvaluation& e, int c, const std::string& q) {
  for (const auto& x : e.cycles)
    if (x.cycle == c && x.value(q)) return *x.value(q);
  throw std::logic_error("no budget " + q);
}
inline double contribution(const uncertainty::Budget& b, const std::string& starts_with) {
  for (const auto& c : b.contributions)
    if (c.input.rfind(starts_with, 0) == 0) return c.u;
  ADD_FAILURE() << b.quantity << " has no contribution '" << starts_with << "'";
  return NAN;
}


// The chosen surfaces (hand-derived errors below):
//  cycle 2: all four facets cut g = 4 um smaller (a warm piece, smaller at 20 C);
//  cycle 3: the table shifted by e = 5 um in +X: X1 at a - e, X2 at a + e;
//  cycle 4: shifted by f = -3 um in Y: Y1 at a - f, Y2 at a + f;
//  cycle 5: Z path cut 7 um deeper; cycle 6: Z path tilted by 20 urad about +Y.
inline Truth chosen(const Fixture& f) {
  Truth t;
  for (const char* s : {"X1", "X2", "Y1", "Y2"}) t.offset_mm[facetId(f, s, 2)] = -0.004;
  t.offset_mm[facetId(f, "X1", 3)] = -0.005;
  t.offset_mm[facetId(f, "X2", 3)] = +0.005;
  t.offset_mm[facetId(f, "Y1", 4)] = +0.003;
  t.offset_mm[facetId(f, "Y2", 4)] = -0.003;
  t.offset_mm[zId(f, 5)] = 0.007;
  t.beta_rad[zId(f, 6)] = 20e-6;
  return t;
}

inline void expectChosenErrors(const TtpEvaluation& e, double tol = 1e-6) {
  // Eq. 7.1 (corrected): E_X = [(d_X2,i - d_X2,0) - (d_X1,i - d_X1,0)] / 2.
  EXPECT_NEAR(value(e, 3, "EX_um"), ((+5.0) - (-5.0)) / 2, tol);
  EXPECT_NEAR(value(e, 2, "EX_um"), ((-4.0) - (-4.0)) / 2, tol);
  EXPECT_NEAR(value(e, 4, "EY_um"), ((-3.0) - (+3.0)) / 2, tol);
  // Eq. 7.3: [dl_X + dl_Y] / 2 with l = d1 + d2: growth -4 um on all four -> (-8 - 8) / 2.
  EXPECT_NEAR(value(e, 2, "ETTP_um"), (-8.0 + -8.0) / 2, tol);
  EXPECT_NEAR(value(e, 3, "ETTP_um"), 0.0, tol);
  // Eq. 7.10: dT = -E_TTP,7.9 / (alpha R) = 4 um / (22e-6 * 97.5 mm).
  EXPECT_NEAR(value(e, 2, "dT_K"), 4.0 / (22e-6 * 97.5e3), 1e-6);
  EXPECT_NEAR(value(e, 5, "EZ_um"), 7.0, tol);
  EXPECT_NEAR(value(e, 5, "EB_urad"), 0.0, 1e-4);
  EXPECT_NEAR(value(e, 6, "EB_urad"), 20.0, 1e-4);
  EXPECT_NEAR(value(e, 6, "EZ_um"), 0.0, tol);  // the tilt leaves the depth at x = 0
  for (int c : {1, 7, 8})
    for (const char* q : {"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um", "dT_K"}) EXPECT_NEAR(value(e, c, q), 0.0, 1e-4) << c << q;
  for (const char* q : {"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um", "dT_K"}) {
    EXPECT_EQ(value(e, 0, q), 0.0);
    EXPECT_EQ(budget(e, 0, q).U, 0.0);
  }
}

}  // namespace probeloop::evaluate::ttptest
