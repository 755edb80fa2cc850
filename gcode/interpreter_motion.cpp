// Motion of a run (interpreter_detail.hpp): targets, rapid and feed moves, arcs as chords, probe
// moves, their results and branches.
#include "gcode/interpreter_detail.hpp"

#include <algorithm>

namespace probeloop::gcode {

void Execution::move(Words& w, bool g53, bool g31) {
  MachinePosition to = target(w, g53);
  if (g31) {
    requireFeed();
    probed(m_.probe(to, feed_, ProbeMode::SkipToTarget), ProbeMode::SkipToTarget);
    return;
  }
  if (isG(motion_, 0)) m_.rapid(to);
  else if (isG(motion_, 1)) {
    requireFeed();
    m_.feed(to, feed_);
  } else if (isG(motion_, 2) || isG(motion_, 3)) {
    requireFeed();
    arc(w, to, isG(motion_, 2));
  } else if (isG(motion_, 38.2) || isG(motion_, 38.3)) {
    requireFeed();
    const auto mode = isG(motion_, 38.2) ? ProbeMode::ErrorWithoutContact : ProbeMode::FlagContact;
    probed(m_.probe(to, feed_, mode), mode);
    return;
  } else {
    fail("axis words with G80 active (no motion mode)");
  }
  pos_ = to;
}

void Execution::requireFeed() {
  if (!(feed_ > 0)) fail("a feed move without a feed rate F");
}

void Execution::probed(const ProbeOutcome& r, ProbeMode mode) {
  if (branching_ && !(mode == ProbeMode::ErrorWithoutContact && !r.contact)) {
    branching_->atProbe(r, [this, mode](const ProbeOutcome& other) {
      Execution branch = *this;
      branch.branching_ = nullptr;  // a branch does not branch again
      return branch.continueAfterProbe(other, mode);
    });
  }
  applyProbe(r, mode);
}

void Execution::applyProbe(const ProbeOutcome& r, ProbeMode mode) {
  if (mode == ProbeMode::ErrorWithoutContact && !r.contact)
    stop(in_.file_, line_, "G38.2 probe move finished without contact");
  if (mode != ProbeMode::SkipToTarget) params_[5070] = r.contact ? 1 : 0;
  setProbeResult(r);
}

InterpreterResult Execution::continueAfterProbe(const ProbeOutcome& other, ProbeMode mode) {
  applyProbe(other, mode);
  if (line_ends_) return InterpreterResult{blocks_, true};
  return runFrom(pc_ + 1);
}

std::array<double, 6> Execution::activeOffset() const {
  auto o = offsets_[static_cast<std::size_t>(wcs_)];
  o[2] += tool_length_;
  return o;
}

MachinePosition Execution::target(Words& w, bool machine_coords) {
  MachinePosition t = pos_;
  const auto off = machine_coords ? std::array<double, 6>{} : activeOffset();
  if (machine_coords && !absolute_) fail("G53 with G91 is not allowed");
  double* dst[] = {&t.xyz_mm.x(), &t.xyz_mm.y(), &t.xyz_mm.z(), &t.a_deg, &t.b_deg, &t.c_deg};
  const double cur[] = {pos_.xyz_mm.x(), pos_.xyz_mm.y(), pos_.xyz_mm.z(), pos_.a_deg, pos_.b_deg, pos_.c_deg};
  const char ax[] = {'X', 'Y', 'Z', 'A', 'B', 'C'};
  for (int a = 0; a < 6; ++a) {
    if (!w.has(ax[a])) continue;
    const double v = w.take(ax[a]);
    *dst[a] = absolute_ ? v + off[static_cast<std::size_t>(a)] : cur[a] + v;
    if (!std::isfinite(*dst[a]))
      fail(std::string("the ") + ax[a] + " target (" + formatG(v) + " plus the offset or the current position) is not a "
           "finite number (overflow); the controller stops here");
  }
  return t;
}

void Execution::setProbeResult(const ProbeOutcome& r) {
  const auto off = activeOffset();
  params_[5061] = r.stop.xyz_mm.x() - off[0];
  params_[5062] = r.stop.xyz_mm.y() - off[1];
  params_[5063] = r.stop.xyz_mm.z() - off[2];
  if (in_.dialect_ == ProgramDialect::LinuxCnc) {
    // LinuxCNC numbers the probed position by axis letter: #5061..#5069 = X Y Z A B C U V W.
    params_[5064] = r.stop.a_deg - off[3];
    params_[5065] = r.stop.b_deg - off[4];
    params_[5066] = r.stop.c_deg - off[5];
  } else {
    // Fanuc numbers the skip position by the control's axis order (#5061 + axis - 1): the
    // X Y Z B C of the NMV 5000. An A/C Fanuc control would read A in #5064; no program we
    // emit reads a rotary skip position.
    params_[5064] = r.stop.b_deg - off[4];
    params_[5065] = r.stop.c_deg - off[5];
  }
  pos_ = r.stop;
}

void Execution::arc(Words& w, const MachinePosition& to, bool clockwise) {
  const Eigen::Vector2d a = pos_.xyz_mm.head<2>(), b = to.xyz_mm.head<2>();
  Eigen::Vector2d centre;
  if (w.has('R')) {
    const double r = w.take('R'), d = (b - a).norm();
    if (std::fabs(r) > 1e5) fail("arc radius R" + formatG(r) + " mm is not plausible");
    if (d < 1e-9 || std::fabs(r) < d / 2 - 1e-9) fail("arc radius R is too small for the end point");
    const double h = std::sqrt(std::max(0.0, r * r - d * d / 4));
    const Eigen::Vector2d mid = (a + b) / 2, perp = Eigen::Vector2d(-(b - a).y(), (b - a).x()) / d;
    // R > 0: the short arc; the centre lies to the right of a->b for G2.
    const double side = (clockwise ? -1.0 : 1.0) * (r > 0 ? 1.0 : -1.0);
    centre = mid + side * h * perp;
  } else {
    if (!w.has('I') && !w.has('J')) fail("G2/G3 needs I/J (centre) or R");
    centre = a + Eigen::Vector2d(w.has('I') ? w.take('I') : 0.0, w.has('J') ? w.take('J') : 0.0);
  }
  const double ra = (a - centre).norm(), rb = (b - centre).norm();
  if (ra < 1e-9) fail("arc with zero radius");
  if (std::fabs(ra - rb) > 0.002) fail("arc end point is not on the arc (radius differs by " + std::to_string(std::fabs(ra - rb)) + " mm)");
  double t0 = std::atan2(a.y() - centre.y(), a.x() - centre.x());
  double t1 = std::atan2(b.y() - centre.y(), b.x() - centre.x());
  double sweep = t1 - t0;
  if (clockwise) {
    if (sweep >= -1e-12) sweep -= 2 * kPi;
  } else if (sweep <= 1e-12) sweep += 2 * kPi;
  if (ra > 1e5) fail("arc radius " + formatG(ra) + " mm is not plausible");
  const double tol = 1e-4;
  const double max_step = 2 * std::acos(std::max(-1.0, 1 - tol / ra));
  const double chords = std::ceil(std::fabs(sweep) / max_step);
  if (!(chords <= 1e6)) fail("arc needs more than 1e6 chords within 0.1 um; not modelled");
  const int n = std::max(1, static_cast<int>(chords));
  for (int k = 1; k <= n; ++k) {
    const double s = static_cast<double>(k) / n;
    MachinePosition p = to;
    if (k < n) {
      const double t = t0 + sweep * s;
      p.xyz_mm.x() = centre.x() + ra * std::cos(t);
      p.xyz_mm.y() = centre.y() + ra * std::sin(t);
      p.xyz_mm.z() = pos_.xyz_mm.z() + (to.xyz_mm.z() - pos_.xyz_mm.z()) * s;
    }
    m_.feed(p, feed_);
  }
}

}  // namespace probeloop::gcode
