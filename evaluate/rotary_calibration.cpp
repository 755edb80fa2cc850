#include "evaluate/rotary_calibration.hpp"

#include <cmath>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "evaluate/budget_json.hpp"
#include "parts/machine_chain.hpp"

namespace probeloop::evaluate {

using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;

namespace {

// One parameter of the model: a location-error component of a body, the table's radial
// growth ER0T, or a component of the sphere's placement.
struct Param {
  std::string name;  // with unit
  int body = -1, component = 0;
  double sign = 1;
  bool radial = false;
  int placement = -1;
};

struct Model {
  geometry::KinematicChain chain;
  std::string tilt;
  Vector3d w0 = Vector3d::Zero();      // sphere centre with every axis at 0 (workpiece frame)
  Vector3d radial = Vector3d::UnitX();  // from the C axis to w0, horizontal
  Eigen::Vector2d c_axis = Eigen::Vector2d::Zero();
  std::vector<const parts::ManifestSphere*> spheres;
};

Model modelOf(const parts::PlanManifest& m) {
  if (!m.tilt_axis) throw InputError(m.file, 0, "the plan tilts no axis: the C axis alone is seed 004's evaluation");
  if (!std::isfinite(m.sphere_centre_height_mm))
    throw InputError(m.file, 0, "artifact.sphere_centre_height_mm: needed for the tilted positions");
  Model md;
  md.tilt = m.tilt_axis->name;
  parts::Machine mc;
  mc.file = m.file;
  mc.c.present = true;
  mc.c.positive_is_clockwise = m.c_positive_is_clockwise;
  mc.c_axis_centre_mm = m.c_axis_centre_mm;
  mc.table_surface_z_mm = m.table_surface_z_mm;
  parts::RotaryAxis& t = md.tilt == "B" ? mc.b : mc.a;
  t.present = true;
  t.positive_is_clockwise = m.tilt_axis->positive_is_clockwise;
  (md.tilt == "B" ? mc.b_axis_centre_xz_mm : mc.a_axis_centre_yz_mm) = m.tilt_axis->centre_mm;
  md.chain = parts::machineChain(mc, m.table_surface_z_mm + m.sphere_centre_height_mm, true);
  for (const auto& s : m.spheres)
    if (s.repeat_of == 0) md.spheres.push_back(&s);
  const auto& s0 = *md.spheres.front();
  const double a0 = degToRad(s0.angle_deg - parts::tableTurnSign(m.c_positive_is_clockwise) * s0.c_deg);
  md.radial = Vector3d(std::cos(a0), std::sin(a0), 0);
  md.c_axis = m.c_axis_centre_mm;
  md.w0 = Vector3d(m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y(), m.table_surface_z_mm + m.sphere_centre_height_mm) +
          m.radius_from_axis_mm * md.radial;
  return md;
}

std::vector<Param> tiltParams(const Model& md) {
  const int t = md.chain.indexOfAxis(md.tilt);
  // The components across the tilting axis: its position (2) and orientation (2).
  const std::vector<int> comps = md.tilt == "B" ? std::vector<int>{0, 2, 3, 5} : std::vector<int>{1, 2, 4, 5};
  std::vector<Param> out;
  for (int k : comps) out.push_back({geometry::locationErrorName(md.tilt, k) + (k < 3 ? "_um" : "_urad"), t, k});
  return out;
}

std::vector<Param> relativeParams(const Model& md) {
  const int c = md.chain.indexOfAxis("C");
  std::vector<Param> p{{"EX0C_um", c, 0},   {"EY0C_um", c, 1},   {"EZ0T_um", c, 2},       {"ER0T_um", -1, 0, 1, true},
                       {"EA0C_urad", c, 3}, {"EB0C_urad", c, 4}, {"EC0C_urad", c, 5, -1}};
  for (auto& q : tiltParams(md)) p.push_back(q);
  return p;
}

std::vector<Param> absoluteParams(const Model& md, bool with_placement) {
  const int c = md.chain.indexOfAxis("C");
  std::vector<Param> p{{"EX0C_um", c, 0}, {"EY0C_um", c, 1}, {"EA0C_urad", c, 3}, {"EB0C_urad", c, 4}};
  for (auto& q : tiltParams(md)) p.push_back(q);
  if (with_placement)
    for (int k = 0; k < 3; ++k) p.push_back({std::string("placement_") + "xyz"[k] + "_um", -1, 0, 1, false, k});
  return p;
}

// A point in parameter space: values (um, urad) of a list of parameters.
struct Values {
  const std::vector<Param>* params;
  VectorXd v;
};

// Sphere centres (mm, stacked x y z per used position) with every list of values applied.
VectorXd observe(const Model& md, const std::vector<Values>& at) {
  geometry::ChainState st;
  const int n = md.chain.bodyCount();
  st.location.resize(static_cast<std::size_t>(n));
  Vector3d w = md.w0;
  double growth_um = 0;
  for (const auto& vs : at)
    for (std::size_t j = 0; j < vs.params->size(); ++j) {
      const Param& q = (*vs.params)[j];
      const double v = vs.v(static_cast<Eigen::Index>(j));
      if (q.radial) growth_um += v;
      else if (q.placement >= 0) w(q.placement) += v * 1e-3;
      else geometry::ChainParameter{q.name, q.body, true, q.component, q.sign}.addTo(st, n, v);
    }
  // The table grows along the radius where the sphere really sits (its placement included),
  // as seed 004's ER0T scales the radius of the centre.
  if (growth_um != 0) {
    const Eigen::Vector2d r = w.head<2>() - md.c_axis;
    w.head<2>() += r.normalized() * growth_um * 1e-3;
  }
  VectorXd out(3 * static_cast<Eigen::Index>(md.spheres.size()));
  for (std::size_t k = 0; k < md.spheres.size(); ++k) {
    st.positions = {{md.tilt, md.spheres[k]->tilt_deg}, {"C", md.spheres[k]->c_deg}};
    out.segment<3>(3 * static_cast<Eigen::Index>(k)) = geometry::machineCoordinatesOf(md.chain, st, w);
  }
  return out;
}

VectorXd observe(const Model& md, const std::vector<Param>& ps, const VectorXd& p) { return observe(md, {{&ps, p}}); }

// um of centre per unit of parameter, at the point `at` (empty: the nominal).
MatrixXd sensitivity(const Model& md, const std::vector<Param>& ps, const std::vector<Values>& at = {}) {
  MatrixXd J(3 * static_cast<Eigen::Index>(md.spheres.size()), static_cast<Eigen::Index>(ps.size()));
  for (std::size_t j = 0; j < ps.size(); ++j) {
    VectorXd e = VectorXd::Zero(static_cast<Eigen::Index>(ps.size()));
    e(static_cast<Eigen::Index>(j)) = 1;
    auto plus = at, minus = at;
    plus.push_back({&ps, e});
    minus.push_back({&ps, -e});
    J.col(static_cast<Eigen::Index>(j)) = (observe(md, plus) - observe(md, minus)) / 2 * 1e3;
  }
  return J;
}

std::vector<std::string> namesOf(const std::vector<Param>& ps) {
  std::vector<std::string> n;
  for (const auto& p : ps) n.push_back(p.name);
  return n;
}

// The parameters' own names without units, for the sentences a user reads.
std::vector<std::string> bareNames(const std::vector<Param>& ps) {
  std::vector<std::string> n;
  for (const auto& p : ps) n.push_back(p.name.substr(0, p.name.rfind('_')));
  return n;
}

void requireIdentifiable(const parts::PlanManifest& m, const MatrixXd& J, const std::vector<Param>& ps, const char* mode) {
  const auto id = geometry::identifiability(J, bareNames(ps));
  if (id.all()) return;
  std::string why;
  for (const auto& s : id.sentences()) why += (why.empty() ? "" : "; ") + s;
  throw GeometryError(m.file + ": the plan's positions cannot separate the " + mode + " location errors: " + why +
                      " (add tilted positions that move the sphere around each axis: `probeloop plan` lists what they identify)");
}

uncertainty::Budget budgetOf(const std::string& name, double value, const VectorXd& weights,
                             const std::vector<const SphereMeasurement*>& now, const std::vector<const SphereMeasurement*>* ref) {
  auto propagated = [&](const std::vector<const SphereMeasurement*>& c) {
    double s = 0;
    for (std::size_t k = 0; k < c.size(); ++k)
      for (int a = 0; a < 3; ++a) {
        const double w = weights(3 * static_cast<Eigen::Index>(k) + a);
        s += w * w * c[k]->centre_budgets[static_cast<std::size_t>(a)].u_c * c[k]->centre_budgets[static_cast<std::size_t>(a)].u_c;
      }
    return std::sqrt(s);
  };
  const std::string unit = name.substr(name.rfind('_') + 1);
  std::vector<uncertainty::Contribution> cs;
  cs.push_back({"sphere centres of this cycle", 'B', "normal",
                "each centre coordinate's budget (probing, resolution, tool change, form, expansion), through the least "
                "squares' sensitivities; positions taken as uncorrelated",
                propagated(now)});
  if (ref)
    cs.push_back({"sphere centres of the reference cycle", 'B', "normal", "as for this cycle, for the reference cycle", propagated(*ref)});
  return uncertainty::combine(name.substr(0, name.rfind('_')), unit, value, cs);
}

std::vector<const SphereMeasurement*> centresOf(const CycleEvaluation& c, const Model& md) {
  std::vector<const SphereMeasurement*> out;
  for (const auto* s : md.spheres) out.push_back(&c.spheres.at(static_cast<std::size_t>(s->position - 1)));
  return out;
}

VectorXd stacked(const std::vector<const SphereMeasurement*>& c) {
  VectorXd y(3 * static_cast<Eigen::Index>(c.size()));
  for (std::size_t k = 0; k < c.size(); ++k) y.segment<3>(3 * static_cast<Eigen::Index>(k)) = c[k]->centre_mm();
  return y;
}

}  // namespace

RotaryIdentifiability rotaryIdentifiability(const parts::PlanManifest& m) {
  const Model md = modelOf(m);
  RotaryIdentifiability r;
  const auto rel = relativeParams(md), abs = absoluteParams(md, true);
  r.relative_names = namesOf(rel);
  r.absolute_names = namesOf(abs);
  r.relative = geometry::identifiability(sensitivity(md, rel), bareNames(rel));
  auto with_zero = rel;
  const int zero_component = md.tilt == "B" ? 4 : 3;
  with_zero.push_back({geometry::locationErrorName(md.tilt, zero_component) + "_urad", md.chain.indexOfAxis(md.tilt), zero_component});
  r.with_tilt_zero = geometry::identifiability(sensitivity(md, with_zero), bareNames(with_zero));
  // The absolute mode also asked for C's zero, the table height and radius: the report shows
  // why they are not in it.
  auto asked = abs;
  const int c = md.chain.indexOfAxis("C");
  asked.push_back({"EC0C_urad", c, 5, -1});
  asked.push_back({"EZ0T_um", c, 2});
  asked.push_back({"ER0T_um", -1, 0, 1, true});
  r.absolute = geometry::identifiability(sensitivity(md, asked), bareNames(asked));
  r.absolute_names = namesOf(asked);
  return r;
}

std::string rotaryIdentifiabilityText(const parts::PlanManifest& m) {
  const auto r = rotaryIdentifiability(m);
  std::ostringstream s;
  auto list = [&](const geometry::Identifiability& id, bool want) {
    std::string out;
    for (std::size_t j = 0; j < id.names.size(); ++j)
      if (id.identifiable[j] == want) out += (out.empty() ? "" : ", ") + id.names[j];
    return out.empty() ? std::string("none") : out;
  };
  s << "Rotary axes (" << m.tilt_axis->name << " and C), identifiability of the planned positions (sensitivity rank):\n";
  auto verdict = [&](const geometry::Identifiability& id) {
    return id.all() ? "; identifies every one: " + list(id, true)
                    : "; identifies " + list(id, true) + "; cannot identify " + list(id, false);
  };
  s << "  drift since cycle 1: rank " << r.relative.rank << " of " << r.relative.names.size() << verdict(r.relative) << "\n";
  for (const auto& t : r.relative.sentences()) s << "    " << t << "\n";
  s << "  absolute (with the sphere's placement): rank " << r.absolute.rank << " of " << r.absolute.names.size()
    << verdict(r.absolute) << "\n";
  for (const auto& t : r.absolute.sentences()) s << "    " << t << "\n";
  s << "  the " << m.tilt_axis->name << " axis's own zero (" << r.with_tilt_zero.names.back()
    << ") is not calibrated: sphere centres cannot tell it from a tilt and a shift of C";
  const auto zs = r.with_tilt_zero.sentences();
  s << (zs.empty() ? std::string(" (these positions would separate it)") : ": " + zs.back()) << "\n";
  return s.str();
}

RotaryCalibration calibrateRotaryAxes(const parts::PlanManifest& m, const CampaignEvaluation& e) {
  const Model md = modelOf(m);
  const auto rel = relativeParams(md), abs = absoluteParams(md, true);
  VectorXd zero_abs = VectorXd::Zero(static_cast<Eigen::Index>(abs.size()));
  const VectorXd nominal = observe(md, abs, zero_abs);
  for (std::size_t k = 0; k < md.spheres.size(); ++k)
    if ((nominal.segment<3>(3 * static_cast<Eigen::Index>(k)) - md.spheres[k]->nominal_centre_mm).norm() > 1e-6)
      throw InputError(m.file, 0, "sphere " + md.spheres[k]->id + ": the plan's nominal centre is not where the machine's chain puts it (" +
                                      m.tilt_axis->name + " axis line, C axis centre, sphere placement); was the plan edited?");
  const MatrixXd J0 = sensitivity(md, abs);
  requireIdentifiable(m, J0, abs, "absolute");
  requireIdentifiable(m, sensitivity(md, rel), rel, "relative");
  // One Gauss-Newton step from the reference cycle's first estimate: the sphere placed 0.1 mm
  // off its nominal changes the levers by 1e-3 of themselves, a bias the nominal sensitivity
  // would leave in every angle. After it, what remains is second order in the errors.
  const auto& ref_cycle = e.cycles.front();
  const auto ref = centresOf(ref_cycle, md);
  const VectorXd y_ref = stacked(ref);
  const VectorXd p0 = (J0.transpose() * J0).ldlt().solve(J0.transpose() * ((y_ref - nominal) * 1e3));
  const std::vector<Values> lin{{&abs, p0}};
  const VectorXd f0 = observe(md, lin);
  const MatrixXd Ja = sensitivity(md, abs, lin), Jr = sensitivity(md, rel, lin);
  const MatrixXd Pa = (Ja.transpose() * Ja).ldlt().solve(Ja.transpose());
  const MatrixXd Pr = (Jr.transpose() * Jr).ldlt().solve(Jr.transpose());

  RotaryCalibration out;
  out.tilt_axis = md.tilt;
  out.relative_names = namesOf(rel);
  for (std::size_t j = 0; j + 3 < abs.size(); ++j) out.absolute_names.push_back(abs[j].name);
  for (const auto* s : md.spheres) out.positions.push_back(s->position);
  out.reference_cycle = e.reference_cycle;
  for (const auto& c : e.cycles) {
    RotaryCycleCalibration rc;
    rc.cycle = c.cycle;
    rc.time_s = c.time_s;
    const auto now = centresOf(c, md);
    const VectorXd y = stacked(now);
    const VectorXd r0 = (y - f0) * 1e3;
    const VectorXd pa = p0 + Pa * r0;
    for (std::size_t j = 0; j < abs.size(); ++j) {
      auto b = budgetOf(abs[j].name, pa(static_cast<Eigen::Index>(j)), Pa.row(static_cast<Eigen::Index>(j)).transpose(), now, nullptr);
      (j + 3 < abs.size() ? rc.absolute : rc.placement).push_back(b);
    }
    const VectorXd res = r0 - Ja * (pa - p0);
    rc.dof = static_cast<int>(r0.size()) - static_cast<int>(abs.size());
    rc.residual_rms_um = rc.dof > 0 ? std::sqrt(res.squaredNorm() / rc.dof) : 0.0;
    if (c.cycle != ref_cycle.cycle) {
      const VectorXd pr = Pr * ((y - y_ref) * 1e3);
      for (std::size_t j = 0; j < rel.size(); ++j)
        rc.relative.push_back(budgetOf(rel[j].name, pr(static_cast<Eigen::Index>(j)), Pr.row(static_cast<Eigen::Index>(j)).transpose(), now, &ref));
    }
    out.cycles.push_back(std::move(rc));
  }
  return out;
}

std::string rotaryCalibrationText(const RotaryCalibration& r) {
  std::ostringstream s;
  const auto& first = r.cycles.front();
  s << "Rotary axes " << r.tilt_axis << " and C on the kinematic chain (" << r.positions.size()
    << " positions; absolute with the sphere's placement, first-order least squares):\n";
  s << "  cycle " << first.cycle << " (absolute):";
  for (const auto& b : first.absolute) s << " " << b.quantity << " " << formatNumber(b.value, 2) << " +- " << formatNumber(b.U, 2) << " " << b.unit << ";";
  s << "\n    residual " << formatNumber(first.residual_rms_um, 3) << " um rms (dof " << first.dof << ")\n";
  const auto& last = r.cycles.back();
  if (!last.relative.empty()) {
    s << "  cycle " << last.cycle << " since cycle " << r.reference_cycle << ":";
    for (const auto& b : last.relative) s << " " << b.quantity << " " << formatNumber(b.value, 2) << " +- " << formatNumber(b.U, 2) << " " << b.unit << ";";
    s << "\n";
  }
  return s.str();
}

std::string rotaryCalibrationJson(const RotaryCalibration& r) {
  nlohmann::ordered_json j;
  j["tilt_axis"] = r.tilt_axis;
  j["reference_cycle"] = r.reference_cycle;
  j["positions"] = r.positions;
  j["absolute_names"] = r.absolute_names;
  j["relative_names"] = r.relative_names;
  j["cycles"] = nlohmann::ordered_json::array();
  for (const auto& c : r.cycles) {
    nlohmann::ordered_json jc{{"cycle", c.cycle}, {"time_s", c.time_s}, {"residual_rms_um", c.residual_rms_um}, {"dof", c.dof}};
    for (const auto& b : c.absolute) jc["absolute"].push_back(budgetJson(b));
    for (const auto& b : c.placement) jc["placement"].push_back(budgetJson(b));
    jc["relative"] = nlohmann::ordered_json::array();
    for (const auto& b : c.relative) jc["relative"].push_back(budgetJson(b));
    j["cycles"].push_back(jc);
  }
  return j.dump(1) + "\n";
}

std::string rotaryErrorSeriesCsv(const RotaryCalibration& r) {
  std::ostringstream s;
  s << "time_s,cycle";
  for (const auto& n : r.relative_names) s << "," << n;
  for (const auto& n : r.relative_names) s << ",U_" << n;
  s << "\n";
  for (const auto& c : r.cycles) {
    s << formatNumber(c.time_s, 3) << "," << c.cycle;
    for (std::size_t j = 0; j < r.relative_names.size(); ++j) s << "," << (c.relative.empty() ? "0" : formatNumber(c.relative[j].value, 4));
    for (std::size_t j = 0; j < r.relative_names.size(); ++j) s << "," << (c.relative.empty() ? "0" : formatNumber(c.relative[j].U, 4));
    s << "\n";
  }
  return s.str();
}

}  // namespace probeloop::evaluate
