// The component-model file (YAML, kind: component_model): fitted error equations as data, each a
// regression family of one input with its coefficients and its source equation, plus which
// stage functions the thermal speed interpolation uses. The shipped instance is seed 000's
// Ch. 5 (examples/stepped_workpiece/yaqoob2017_components.yaml); docs/stepped-workpiece.md.
//
//   kind: component_model
//   source: "..."
//   equations:
//     - {id: e_pos_x, equation: "Eq. 5.1", family: polynomial, input: dx_mm, unit: mm,
//        coefficients: [0, 0.000249252, -9.57162e-7]}          # a polynomial: c0, c1, ...
//     - {id: e_pt_x_s1, equation: "Eq. 5.6", family: saturating_exponential, input: T_min,
//        unit: mm, coefficients: {a: 0.0333374, b: 0.0333374, c: 0.0188882},
//        reading: "how a typo was read"}                        # reading: optional
//   thermal:                                                     # optional
//     - {component: e_pt_x, equations: "Eq. 5.21-5.24", stage_1000_rpm: <id>,
//        stage_3500_rpm: <id>, stage_5500_rpm: <id>}
//   control: {feed_low_mm_per_min: 100, feed_high_mm_per_min: 2400}   # optional
//
// Contract: loadComponentModel throws InputError with file:line for an unknown kind, key,
// family, input or unit; coefficients missing, unknown or not finite; an id listed twice; a
// thermal entry naming an equation that does not exist or whose input is not T_min; a control
// block with feed_high <= feed_low.
#pragma once
#include <string>
#include <vector>

#include "model/regression_family.hpp"

namespace probeloop::parts {

struct ComponentEquation {
  std::string id, equation;  // "e_pt_x_s1", "Eq. 5.6"
  std::string input;         // T_min, dx_mm, dy_mm, dz_mm, feed_{x,y,z,xy}_mm_per_min, e_prog
  std::string unit;          // mm or slope
  std::string reading;       // how a typo of the source was read ("" = as printed)
  model::RegressionFunction function;
  int line = 0;              // where it is in the file
  double operator()(double x) const { return function.evaluate(x); }
};

// One thermal component's stage functions at the speed nodes (seed 000 Eq. 3.7-3.10).
struct ThermalStages {
  std::string component, equations;
  std::string stage_1000_rpm, stage_3500_rpm, stage_5500_rpm;  // equation ids
};

struct ComponentModel {
  std::string file, source;
  std::vector<ComponentEquation> equations;
  std::vector<ThermalStages> thermal;
  double control_feed_low_mm_per_min = 100, control_feed_high_mm_per_min = 2400;

  const ComponentEquation& equation(const std::string& id) const;  // std::out_of_range naming the ids
  const ThermalStages& stages(const std::string& component) const;  // std::out_of_range naming them
};

ComponentModel loadComponentModel(const std::string& path);

// The inputs and units the file may name.
const std::vector<std::string>& componentInputs();
const std::vector<std::string>& componentUnits();

}  // namespace probeloop::parts
