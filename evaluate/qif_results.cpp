#include "evaluate/qif_results.hpp"

#include <map>

#include "core/csv.hpp"
#include "interop/measured_geometry.hpp"
#include "interop/qif.hpp"
#include "parts/cmm_feature.hpp"

namespace probeloop::evaluate {

std::string evaluationQif(const parts::PlanManifest& m, const TtpPoints* points, const std::string& errors_csv) {
  interop::CmmDocument d;
  d.part_name = m.part_name;
  if (points) {
    std::map<std::string, std::size_t> index;
    for (const auto& p : points->points) {
      auto it = index.find(p.feature);
      if (it == index.end()) {
        const auto* mf = m.feature(p.feature);
        if (!mf) continue;  // the readers assign only manifest features
        it = index.emplace(p.feature, d.features.size()).first;
        d.features.push_back(parts::cmmFeatureOf(mf->nominal));
      }
      interop::CmmPoint q;
      q.p_mm = p.p_mm;
      d.features[it->second].points.push_back(q);
    }
    for (auto& f : d.features) interop::fitMeasuredGeometry(f);
  }
  const CsvTable t = parseCsv(errors_csv, "errors.csv");
  const int cycle = t.column("cycle"), step = t.column("step");
  const int id_col = cycle >= 0 ? cycle : step;
  const std::string id_name = cycle >= 0 ? "cycle" : "step";
  for (const auto& row : t.rows) {
    const std::string id = id_col >= 0 ? row.fields[static_cast<std::size_t>(id_col)] : std::to_string(row.line);
    for (std::size_t c = 0; c < t.header.size(); ++c) {
      const std::string& h = t.header[c];
      const bool um = h.ends_with("_um"), urad = h.ends_with("_urad");
      if ((!um && !urad) || h.rfind("U_", 0) == 0 || h.rfind("u_", 0) == 0) continue;
      double v = 0;
      if (!t.tryNumber(row, static_cast<int>(c), v)) continue;
      interop::CmmCharacteristic ch;
      ch.name = h.substr(0, h.size() - (um ? 3 : 5)) + " " + id_name + " " + id;
      ch.angular = urad;
      ch.value = v * 1e-3 * (urad ? 1e-3 : 1.0);
      double u = 0;
      if (t.column("u_" + h) >= 0 && t.tryNumber(row, t.column("u_" + h), u))
        ch.u = u * 1e-3 * (urad ? 1e-3 : 1.0);
      else if (t.column("U_" + h) >= 0 && t.tryNumber(row, t.column("U_" + h), u))
        ch.u = u / 2 * 1e-3 * (urad ? 1e-3 : 1.0);
      d.characteristics.push_back(ch);
    }
  }
  return interop::qifResults(d);
}

}  // namespace probeloop::evaluate
