// The stepped workpiece's material as the programs leave it, box by box, and the collision
// check of every motion against it (sw_detail.hpp).
#include "planner/sw_detail.hpp"

#include <algorithm>
#include <cmath>
#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::planner::sw {

std::string xyz(const Vector3d& v) {
  return "(" + formatNumber(v.x(), 4) + ", " + formatNumber(v.y(), 4) + ", " + formatNumber(v.z(), 4) + ")";
}

std::vector<Material::Box> Material::boxes() const {
  const double m = w.finishing_margin_mm, c_bottom = w.blankTopZ() - w.blank_height_mm;
  const double bx = w.blank_x_mm / 2, by = w.blank_y_mm / 2;
  if (blank)
    return {{bx, by, c_bottom, w.blankTopZ()},
            {w.fixture_diameter_mm / 2, w.fixture_diameter_mm / 2, c_bottom - w.fixture_height_mm, c_bottom}};
  std::vector<Box> out;
  const std::size_t n = half.size();
  const auto shift = [](const std::vector<double>& v, std::size_t j) { return j < v.size() ? v[j] : 0.0; };
  // Box j's top: the floor of step j - 1 (0: the top face), where its compensated pass cut it
  // once finished, the margin above the nominal floor before; its bottom: its own floor,
  // reaching down to a floor the compensation lowered.
  for (std::size_t j = 0; j < n; ++j) {
    const bool top_done = static_cast<int>(j) < tops_finished;
    const double top = j == 0 ? 0.0 : -w.steps[j - 1].floor_depth_mm + (top_done ? shift(floor_up, j - 1) : 0.0);
    const double h = half[j] + (static_cast<int>(j) < walls_finished ? shift(wall_out, j) : m);
    const double z_hi = top + (top_done ? 0.0 : m);
    out.push_back({h, h, -w.steps[j].floor_depth_mm + std::min(shift(floor_up, j), 0.0), z_hi});
  }
  const bool base_done = static_cast<int>(n) < tops_finished;
  const double base_top = -w.steps.back().floor_depth_mm + (base_done ? shift(floor_up, n - 1) : m);
  out.push_back({bx, by, c_bottom, base_top});
  // The fixture under the blank (a box round its circle: the safe side).
  out.push_back({w.fixture_diameter_mm / 2, w.fixture_diameter_mm / 2, c_bottom - w.fixture_height_mm, c_bottom});
  return out;
}

// Distance in XY from p to the rectangle |x| <= hx, |y| <= hy (0 inside).
double rectDistance(const Vector2d& p, double hx, double hy) {
  const double dx = std::max(std::fabs(p.x()) - hx, 0.0), dy = std::max(std::fabs(p.y()) - hy, 0.0);
  return std::hypot(dx, dy);
}

void Builder::check(const Motion& mo, const Material& mat) const {
  const std::string tool = mo.tool.probe ? "probe" : "tool T" + std::to_string(mo.tool.number);
  auto fail = [&](const std::string& msg) { throw SafetyError(*mo.program + ": " + mo.note->where + ": " + msg); };
  const Vector3d off = O_ + Vector3d(c_, c_, 0);
  const Vector3d qa = mo.from_tip - off, qb = mo.to_tip - off;  // relative to the steps' centre, part z
  const double rho = mo.tool.radius_mm, below = mo.tool.probe ? rho : 0.0;
  const double top = mat.blank ? w_.blankTopZ() : mat.boxes().front().z_hi;
  if (mo.kind == MotionKind::Rapid && std::min(qa.z(), qb.z()) - below < top - 1e-9) {
    int axes = 0;
    for (int i = 0; i < 3; ++i) axes += std::fabs(qa(i) - qb(i)) > 1e-3;
    if (axes > 1)
      fail("G0 from " + xyz(mo.from_tip) + " to " + xyz(mo.to_tip) + " moves " + std::to_string(axes) + " axes with the " + tool +
           " below the top of the part (a G0 may dog-leg: only G1 there)");
  }
  if (mo.note->cut || mo.note->retract || mo.kind == MotionKind::Measuring) return;
  if (mo.kind == MotionKind::MachineZ && qb.z() >= qa.z()) return;  // straight up to the tool-change height
  // Straight up: in every state the material only narrows upward (roughing clears each level
  // at least as wide as the one below it; the steps shrink upward), so nothing is met.
  if ((qa.head<2>() - qb.head<2>()).norm() < 1e-9 && qb.z() >= qa.z()) return;
  const auto boxes = mat.boxes();
  // Samples 0.02 mm apart: a graze between two of them stays under 0.01 mm.
  const double len = (qb - qa).norm();
  const int n = std::max(1, static_cast<int>(std::ceil(len / 0.02)));
  for (int i = 0; i <= n; ++i) {
    const Vector3d q = qa + (qb - qa) * (static_cast<double>(i) / n);
    for (const auto& b : boxes) {
      if (q.z() - below >= b.z_hi - 1e-6) continue;
      const double d = rectDistance(q.head<2>(), b.hx, b.hy);
      if (d < rho - 1e-6)
        fail(std::string(mo.what) + " from " + xyz(mo.from_tip) + " to " + xyz(mo.to_tip) + " would take the " + tool +
             " into material at " + xyz(q + off) + ": " + formatNumber(d, 3) + " mm from a face, its radius " +
             formatNumber(rho, 3) + " mm");
    }
  }
}

}  // namespace probeloop::planner::sw
