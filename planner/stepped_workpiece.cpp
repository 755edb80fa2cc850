#include "planner/stepped_workpiece.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "planner/piece_manifest.hpp"
#include "planner/piece_program.hpp"
#include "planner/sw_detail.hpp"

namespace probeloop::planner {

using Eigen::Vector2d;
using Eigen::Vector3d;
using parts::SteppedWorkpiece;


namespace sw {

Builder::Builder(const SteppedWorkpiece& w, const std::string& experiment, const parts::Machine& m, parts::Dialect d,
        const parts::SwCompensation* comp)
    : w_(w), m_(m), dialect_(d), files_(swFiles(d)), material_{w, {}, {}, {}} {
  comp_ = comp;
  e_ = w.experiment(experiment);
  if (comp_)
    for (const auto& s : comp_->steps) {
      material_.wall_out.push_back(-toProgram(std::min({s.wall_um[0], s.wall_um[1], s.wall_um[2], s.wall_um[3]})));
      material_.floor_up.push_back(toProgram(s.floor_um));
    }
  if (!e_) {
    std::string ids;
    for (const auto& x : w.experiments) ids += (ids.empty() ? "" : ", ") + x.id;
    throw InputError(w.file, 0, "experiments: no experiment '" + experiment + "' (the description has " + ids + ")");
  }
  if (comp_ && comp_->experiment != e_->id)
    throw InputError(comp_->file, 0, "experiment: '" + comp_->experiment + "', but " + e_->id +
                                         " is planned (its errors belong to its own feeds and times)");
  if (comp_ && comp_->steps.size() != e_->steps.size())
    throw InputError(comp_->file, 0, "steps: " + std::to_string(comp_->steps.size()) + " given, experiment " + e_->id + " has " +
                                         std::to_string(e_->steps.size()));
  // Roughing leaves the finishing margin: a wall moved out or a floor raised by more would be
  // cut in the air and stay where roughing left it.
  if (comp_)
    for (std::size_t k = 0; k < comp_->steps.size(); ++k) {
      const auto& c = comp_->steps[k];
      const double mrg_um = w.finishing_margin_mm * 1e3;
      for (int i = 0; i < 4; ++i)
        if (c.wall_um[static_cast<std::size_t>(i)] < -mrg_um)
          throw InputError(comp_->file, 0, "steps[" + std::to_string(k) + "].wall_um." + parts::kSwWalls[i] + ": " +
                                               formatNumber(c.wall_um[static_cast<std::size_t>(i)]) + " um moves the wall out by more "
                                               "than the finishing margin (" + formatNumber(mrg_um) + " um) roughing leaves");
      if (c.floor_um > mrg_um)
        throw InputError(comp_->file, 0, "steps[" + std::to_string(k) + "].floor_um: " + formatNumber(c.floor_um) +
                                             " um raises the floor by more than the finishing margin (" + formatNumber(mrg_um) + " um)");
    }
  sizes_ = w.sizesFor(*e_);
  for (double s : sizes_) material_.half.push_back(s / 2);
  features_ = parts::nominalFeatures(w, sizes_);
  O_ = parts::steppedWorkpieceOrigin(w, m);
  tool_ = &w.finishingTool();
  r_ = tool_->diameter_mm / 2;
  rt_ = w.probing.tip_diameter_mm / 2;
  c_ = w.centreXY();
  // Square contours cover their corners only with a step of at most r sqrt 2.
  step_ = std::min(w.machining.stepover * tool_->diameter_mm, r_ * std::sqrt(2.0) - 0.01);
  z_clear_ = w.blankTopZ() + w.machining.clearance_mm;
  checkInputs();
}

SteppedWorkpiecePlan Builder::build() {
  for (std::size_t i = 0; i < features_.size(); ++i) {
    parts::ManifestFeature f;
    f.nominal = features_[i];
    f.position = static_cast<int>(i + 1);  // the probing program visits them in this order
    man_.features.push_back(f);
  }
  roughing();
  finishing();
  probing();
  walk();
  manifest();
  plan_.experiment = e_->id;
  plan_.sizes_mm = sizes_;
  plan_.programs = std::move(programs_);
  plan_.manifest = std::move(man_);
  plan_.cmm_points_csv = cmmCsv();
  return std::move(plan_);
}

void Builder::checkInputs() const {
  const double f_xy = std::min(m_.x.max_feed_mm_per_min, m_.y.max_feed_mm_per_min), f_z = m_.z.max_feed_mm_per_min;
  const std::string key = "experiments[" + e_->id + "]";
  auto feed = [&](double v, double max, const std::string& k, const char* axes) {
    if (!(v <= max))
      throw InputError(w_.file, 0, k + ": " + formatNumber(v) + " mm/min exceeds the machine's " + axes + " max_feed of " +
                                       formatNumber(max) + " mm/min (" + m_.file + ")");
  };
  for (std::size_t k = 0; k < e_->steps.size(); ++k) {
    const auto& s = e_->steps[k];
    const std::string sk = key + ".steps[" + std::to_string(k + 1) + "]";
    feed(s.feed_xy_mm_per_min, f_xy, sk + ".feed_xy", "X/Y");
    feed(s.feed_z_mm_per_min, f_z, sk + ".feed_z", "Z");
  }
  if (e_->transition != "continuous") feed(e_->transition_feed_mm_per_min, f_xy, key + ".transition_feed", "X/Y");
  feed(w_.machining.roughing_feed_xy_mm_per_min, f_xy, "machining.roughing.feed_xy", "X/Y");
  feed(w_.probing.feed_mm_per_min, std::min(f_xy, f_z), "probing.feed", "X/Y/Z");
  feed(w_.probing.positioning_feed_mm_per_min, std::min(f_xy, f_z), "probing.positioning_feed", "X/Y/Z");
  // Z reach: the gauge line at the deepest cut and at the clearance plane within the travel.
  const double deepest = O_.z() - w_.steps.back().floor_depth_mm, clear = O_.z() + z_clear_;
  auto reach = [&](double length, double lowest_tip, const std::string& k, const std::string& what) {
    if (clear + length > m_.z.max_mm + 1e-9)
      throw InputError(w_.file, 0, k + ": " + formatNumber(length) + " mm: " + what + " at the clearance plane (tip Z " +
                                       formatNumber(round4(clear)) + ") puts the gauge line at Z " + formatNumber(round4(clear + length)) +
                                       ", above the Z travel (max " + formatNumber(m_.z.max_mm) + " mm, " + m_.file + ")");
    if (lowest_tip + length < m_.z.min_mm - 1e-9)
      throw InputError(w_.file, 0, k + ": " + formatNumber(length) + " mm: " + what + " cannot reach down to tip Z " +
                                       formatNumber(round4(lowest_tip)) + " within the Z travel (gauge line min " +
                                       formatNumber(m_.z.min_mm) + " mm, " + m_.file + "): it needs at least " +
                                       formatNumber(round4(m_.z.min_mm - lowest_tip)) + " mm");
  };
  reach(tool_->length_mm, deepest, "tools[T" + std::to_string(tool_->number) + "].length", "the finishing tool");
  // A tool is changed at the tool-change height: the new tool (or the probe) must hang
  // above the clearance plane there, or it is loaded (and the spindle started) in the part.
  auto hangs = [&](double length, double tip_z, const std::string& what) {
    if (m_.tool_change.z_mm - length < tip_z - 1e-9)
      throw InputError(m_.file, 0, "tool_change.z: " + formatNumber(m_.tool_change.z_mm) + " mm puts the tip of " + what + " (" +
                                       formatNumber(length) + " mm) at Z " + formatNumber(round4(m_.tool_change.z_mm - length)) +
                                       ", below the clearance plane of " + w_.file + " (tip Z " + formatNumber(round4(tip_z)) + ")");
  };
  hangs(tool_->length_mm, clear, "tool T" + std::to_string(tool_->number));
  hangs(m_.probe.length_mm, O_.z() + rt_ + w_.machining.clearance_mm, "the probe");
  if (!(step_ > 0.1))
    throw InputError(w_.file, 0, "tools[T" + std::to_string(tool_->number) + "].diameter: " + formatNumber(tool_->diameter_mm) +
                                     " mm is too small for the contours (step " + formatNumber(step_) + " mm)");
  reach(m_.probe.length_mm, deepest + rt_, "probe.length (" + m_.file + ")", "the probe");
}

}  // namespace sw

SwFiles swFiles(parts::Dialect d) {
  const std::string ext = programExtension(d);
  SwFiles f;
  f.roughing = "roughing" + ext;
  f.finishing = "finishing" + ext;
  f.probing = "probing" + ext;
  return f;
}

SteppedWorkpiecePlan planSteppedWorkpiece(const SteppedWorkpiece& w, const std::string& experiment, const parts::Machine& m,
                                          parts::Dialect dialect, const parts::SwCompensation* compensation) {
  return sw::Builder(w, experiment, m, dialect, compensation).build();
}

std::string swProgramText(const NotedProgram& p, parts::Dialect dialect) {
  return programText(p, dialect);
}

}  // namespace probeloop::planner
