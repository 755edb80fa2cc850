// The planner's prediction for the thermal test piece (contract in thermal_test_piece.hpp,
// docs/thermal-test-piece-evaluation.md): the evaluation of the planned points on the CMM and
// on-machine routes, type B scatter only, and the largest U of every value over the cycles.
#include <string>
#include <vector>

#include "core/error.hpp"
#include "evaluate/ttp_detail.hpp"

namespace probeloop::evaluate {

using ttp::evaluateImpl;
using ttp::kQuantities;
using ttp::kUnits;

// --- the planner's prediction -----------------------------------------------------------------

TtpPrediction predictThermalTestPiece(const parts::PlanManifest& m, double k) {
  TtpPrediction out;
  if (m.points.empty()) {
    out.note = "the manifest lists no probe points: nothing to predict";
    return out;
  }
  TtpPoints pts;
  pts.file = m.file;
  pts.assigned_by = "labels";
  for (const auto& p : m.points) {
    TtpPoint q;
    q.feature = p.feature;
    q.point = p.point;
    q.p_mm = machineToPart(m, p.contact_mm + m.tip_radius_mm * p.approach.normalized(), p.c_deg);
    pts.points.push_back(q);
  }
  TtpOptions o;
  o.coverage_k = k;
  o.form_mz = false;
  for (TtpRoute route : {TtpRoute::Cmm, TtpRoute::OnMachine}) {
    pts.route = route;
    TtpEvaluation e;
    try {
      e = evaluateImpl(m, pts, o, true);
    } catch (const InputError& x) {
      out.note = std::string("no prediction from the planned points: ") + x.what();
      return out;
    }
    auto& dst = route == TtpRoute::Cmm ? out.cmm : out.on_machine;
    for (int j = 0; j < 6; ++j) {
      TtpPredictedValue best;
      best.quantity = kQuantities[j];
      best.unit = kUnits[j];
      bool any = false;
      for (const auto& c : e.cycles) {
        if (c.cycle == 0) continue;
        const auto* b = c.value(kQuantities[j]);
        if (!b) continue;
        if (!any || b->U > best.U) {
          best.U = b->U;
          best.cycle = c.cycle;
          best.largest = b->contributions.empty() ? "" : b->contributions.front().input;
          any = true;
        }
      }
      if (any) dst.push_back(best);
    }
  }
  return out;
}

}  // namespace probeloop::evaluate
