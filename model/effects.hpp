// The effects library (docs/architecture.md#how-to-add-an-effect): the physical error effects, written once, used as
// truth by the simulator (sim/) and as model terms and diagnosis candidates here.
//
// Two layers:
// - the physics primitives the simulator steps through time (lagStep, decayStep,
//   expansion_um): exact for inputs held constant over a step, so a campaign does not
//   depend on how time is cut into steps;
// - Effect: a model term of one error channel, which turns the machine's logged inputs
//   (inputs.csv) into a regressor on the inputs' time base.
//
// Effect kinds (docs/model.md lists them with their physics):
//   offset     c                                   (every channel has one implicitly)
//   drift      b t                                 (non-physical: a stand-in for a slow source)
//   static     k (u - u0)                          a sensor, no delay (Blaser's static model)
//   lag        k x,  tau dx/dt = g(u) - x          first-order lag of a sensor or of a heat-
//                                                  source proxy; g(u) = |u| for speeds and feed
//   transient  k s,  s jumps by each event, tau ds/dt = -s   (tool changes: a settling step)
//   expansion  alpha L (T - T0)                    artifact/workpiece/table growth; alpha and
//                                                  L are known, nothing is fitted
//   force      c F                                 force-induced deflection: a compliance c
//                                                  (um/N) times a cutting-force input (a column
//                                                  in N, e.g. F_y_N); seed 003's F/(4k) and
//                                                  F R/(k S^2) x arm are both linear in F
//                                                  (model/structural_stiffness.hpp)
// A static or lag effect may act over a lever: its regressor times another inputs column
// (`lever`), e.g. lag(spindle_rpm) x travel_mm: a warmed screw or frame stretches its axis, an
// error that grows with the heat and with the distance (seed 000's thermal position error e_pt).
// Contract: regressor() is finite for finite inputs; tau > 0; an input column that does not
// exist is an InputError naming the columns there are.
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace probeloop::model {

// x after dt of tau dx/dt = u - x with u held (exact; tau > 0, dt >= 0).
double lagStep(double x, double u, double dt_s, double tau_s);
// s after dt of tau ds/dt = -s.
double decayStep(double s, double dt_s, double tau_s);
// Thermal growth alpha L dT (alpha in um/(m K), L in mm) in um.
double expansion_um(double alpha_um_per_m_K, double length_mm, double dT_K);

// How the channels of an evaluation read the part's own growth (the expansion effect's known
// levers, from the part's description: parts::expansionLevers): a channel reads alpha L dT of
// the part's temperature change, L signed (mm), keyed by the channel's name without its unit
// suffix (EZ0T, ER0T; EZ, ETTP ...).
struct ExpansionLevers {
  double alpha_um_per_m_K = 0;
  std::map<std::string, double> length_mm;
  std::string what = "artifact";  // "artifact", "test piece": the diagnosis's sentences name it
  std::optional<double> lengthFor(const std::string& channel) const;
};

enum class EffectKind { Offset, Drift, Static, Lag, Transient, Expansion, Force };

struct Effect {
  EffectKind kind = EffectKind::Offset;
  std::string input;                 // inputs.csv column (static, lag, transient, expansion)
  std::optional<double> tau_s;       // lag/transient: start value (or the fixed value)
  bool tau_fixed = false;
  double alpha_um_per_m_K = 0;       // expansion
  double length_mm = 0;              // expansion
  std::string lever;                 // static/lag: the regressor times this inputs column ("" none)
  bool just_added = false;           // set by `probeloop model add`: "before" leaves it out

  std::string id() const;            // e.g. "lag(c_rpm)", "offset", "expansion(T_table_C)", "lag(spindle_rpm)*travel_mm",
                                     // "force(F_y_N)"
  bool hasTimeConstant() const { return kind == EffectKind::Lag || kind == EffectKind::Transient; }
  bool fitsGain() const { return kind != EffectKind::Expansion; }
};

Effect makeEffect(EffectKind kind, const std::string& input = "");
const char* kindName(EffectKind k);
std::optional<EffectKind> kindFromName(const std::string& name);

// A heat-source proxy is driven by its magnitude (a speed heats whichever way it turns).
bool isSpeedInput(const std::string& column);
// A force input: a column in newtons (name ending in _N, e.g. F_y_N).
bool isForceInput(const std::string& column);

// The regressor of an effect on a uniform time grid (t[0], t[0] + step, ...), from the input
// column u on that grid; tau_s for lag/transient. A lag starts in equilibrium with u[0]; a
// transient starts at rest and an event counted in sample k happened half a step before t_k.
// Expansion returns alpha L (T - T[0]) in um (the fixed prediction, not a regressor). Force
// returns F itself (no force, no deflection; the channel's offset is its error at F = 0).
std::vector<double> regressor(const Effect& e, const std::vector<double>& t_s, const std::vector<double>& u,
                              double tau_s);

}  // namespace probeloop::model
