#include "parts/piece_kinds.hpp"

#include "core/error.hpp"
#include "core/units.hpp"

namespace probeloop::parts {

namespace {

TestPiece fromSphereArtifact(SphereArtifact a) {
  TestPiece t;
  t.kind = "sphere_artifact";
  t.file = a.file;
  t.name = "sphere artifact";
  // Part frame = the table frame at C = 0, origin on the C axis in the table surface.
  NominalFeature s;
  s.id = "SPHERE";
  s.kind = "sphere";
  s.role = "sphere";
  s.group = "sphere";
  const double th = degToRad(a.angle_at_c0_deg);
  s.point_mm = Eigen::Vector3d(a.radius_from_axis_mm * std::cos(th), a.radius_from_axis_mm * std::sin(th),
                               a.centreHeightAboveTable());
  s.radius_mm = a.sphereRadius();
  t.features.push_back(s);
  t.evaluation = sphereArtifactEvaluation();
  t.description = std::move(a);
  return t;
}

TestPiece fromThermalTestPiece(ThermalTestPiece p) {
  TestPiece t;
  t.kind = "thermal_test_piece";
  t.file = p.file;
  t.name = p.name;
  t.features = nominalFeatures(p);
  t.stock = thermalTestPieceWorkpiece(p);
  t.evaluation = thermalTestPieceEvaluation();
  t.description = std::move(p);
  return t;
}

// The stepped workpiece's features are the standard step sizes; an experiment cut to the
// alternative set (W2, W5) gets its own from nominalFeatures(w, w.sizesFor(e)). Its planner,
// simulation and evaluation are the rest of issue 14.
TestPiece fromSteppedWorkpiece(SteppedWorkpiece w) {
  TestPiece t;
  t.kind = "stepped_workpiece";
  t.file = w.file;
  t.name = w.name;
  t.features = nominalFeatures(w);
  t.stock = steppedWorkpieceStock(w);
  t.description = std::move(w);
  return t;
}

TestPiece fromWorkpiece(Workpiece w) {
  TestPiece t;
  t.kind = "workpiece";
  t.file = w.file;
  t.name = w.name;
  t.stock = w;
  t.description = std::move(w);
  return t;
}

}  // namespace

const std::vector<std::string>& testPieceKinds() {
  static const std::vector<std::string> kinds{"sphere_artifact", "thermal_test_piece", "stepped_workpiece", "workpiece"};
  return kinds;
}

TestPiece loadTestPiece(const std::string& path) {
  const std::string kind = partKind(path);
  if (kind == "sphere_artifact") return fromSphereArtifact(loadSphereArtifact(path));
  if (kind == "thermal_test_piece") return fromThermalTestPiece(loadThermalTestPiece(path));
  if (kind == "stepped_workpiece") return fromSteppedWorkpiece(loadSteppedWorkpiece(path));
  if (kind == "workpiece") return fromWorkpiece(loadWorkpiece(path));
  std::string list;
  for (const auto& k : testPieceKinds()) list += (list.empty() ? "" : ", ") + k;
  throw InputError(path, 1, "kind: '" + kind + "' is not a kind of test piece probeloop knows (" + list + ")");
}

model::ExpansionLevers expansionLevers(const TestPiece& piece) {
  model::ExpansionLevers out;
  if (const auto* a = piece.sphereArtifact()) {
    if (!(a->alpha_um_per_m_K > 0))
      throw InputError(piece.file, 0, "uncertainty.alpha_um_per_m_K: the expansion candidates need the artifact's expansion coefficient");
    out.alpha_um_per_m_K = a->alpha_um_per_m_K;
    out.length_mm = {{"EZ0T", a->centreHeightAboveTable() + a->sphereRadius()}, {"ER0T", a->radius_from_axis_mm}};
    out.what = "artifact";
    return out;
  }
  if (const auto* t = piece.thermalTestPiece()) {
    if (!(t->material.alpha_um_per_m_K > 0))
      throw InputError(piece.file, 0, "blank.material.alpha_um_per_m_K: the expansion candidates need the piece's expansion coefficient");
    // Table -> Z path floor: the adapter and the washers (same alloy, L1998) and the piece
    // below the path all follow the piece's temperature.
    const double path_height = t->supportHeight() + t->finishedHeight() + t->cuttingZ();
    out.alpha_um_per_m_K = t->material.alpha_um_per_m_K;
    out.length_mm = {{"EZ", path_height}, {"ETTP", -2 * t->facet_apothem_mm}};
    out.what = "test piece";
    return out;
  }
  throw InputError(piece.file, 1, "kind: " + piece.kind + " has no evaluation, so no expansion levers: give --alpha-um-per-m-K and --length-mm");
}

std::vector<EvaluationRule> sphereArtifactEvaluation() {
  const std::string f = "the sphere centre at every C position of a cycle, relative to the reference cycle";
  return {
      {"EX0C_um", "mean x of the centres", "seed 004 Eq. 5.4; least squares (docs/location-errors.md)", f},
      {"EY0C_um", "mean y of the centres", "seed 004 Eq. 5.5", f},
      {"EZ0T_um", "mean z of the centres", "seed 004 Eq. 5.6", f},
      {"ER0T_um", "(x3 + y2 - x1 - y4) / 4", "seed 004 Eq. 5.7", f},
      {"EA0C_urad", "(z2 - z4) / d", "seed 004 Eq. 5.8", f},
      {"EB0C_urad", "(z1 - z3) / d", "seed 004 Eq. 5.9", f},
      {"EC0C_urad", "(y1 + x2 - y3 - x4) / (2 d)", "seed 004 Eq. 5.10", f},
  };
}

std::vector<EvaluationRule> thermalTestPieceEvaluation() {
  const std::string facets = "facets X1_k, X2_k, Y1_k, Y2_k of cycle i and of the reference cycle 0";
  return {
      {"EX_um", "[(d_X2(ti) - d_X2(t0)) - (d_X1(ti) - d_X1(t0))] / 2",
       "seed 004 Eq. 7.1, last term's sign corrected (notes/seed004.md §11 item 10); the printed form is reported beside it", facets},
      {"EY_um", "[(d_Y2(ti) - d_Y2(t0)) - (d_Y1(ti) - d_Y1(t0))] / 2", "seed 004 Eq. 7.2, sign corrected likewise", facets},
      {"EZ_um", "d_Z(ti) - d_Z(t0)", "seed 004 Eq. 7.4", "Z paths of cycle i and of the reference cycle"},
      {"EB_urad", "beta(ti) - beta(t0), beta = atan2(n_x, n_z) of the LS plane", "seed 004 Eq. 7.5",
       "Z paths of cycle i and of the reference cycle"},
      {"ETTP_um", "[l_X(ti) - l_X(t0) + l_Y(ti) - l_Y(t0)] / 2, l = d_1 + d_2",
       "seed 004 Eq. 7.3 (diametral); Eq. 7.9, half of it, is reported beside it", facets},
      {"dT_K", "-E_TTP,7.9 / (alpha R)",
       "seed 004 Eq. 7.10 (alpha, R from the description); minus: a piece cut warm is smaller at 20 C (docs/thermal-test-piece.md §4)",
       "E_TTP (radial, Eq. 7.9 form)"},
  };
}

}  // namespace probeloop::parts
