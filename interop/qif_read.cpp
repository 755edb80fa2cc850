// Reading QIF 3.0 Plan and Results documents (interop/qif.hpp has the contract): features,
// their nominal and measured geometry and points, characteristics; and the lenient reading of
// what producers get wrong without changing the meaning (docs/interop.md#lenient-reading).
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "interop/qif.hpp"
#include "interop/qif_xml.hpp"

namespace probeloop::interop {

using namespace qifxml;

CmmDocument parseQifPlan(const std::string& xml, const std::string& file_name) {
  auto q = openQif(xml, file_name, false);
  auto& r = q.r;
  auto& d = q.d;
  const auto* fs = child(q.root, "Features");
  std::map<std::string, const xmlNode*> defs, sets;
  std::map<std::string, std::string> item_name;  // by nominal id
  for (const auto* e : children(child(fs, "FeatureDefinitions"))) defs[attribute(e, "id")] = e;
  for (const auto* e : children(child(fs, "NominalPointSets"), "NominalPointSet")) sets[attribute(e, "id")] = e;
  for (const auto* it : children(child(fs, "FeatureItems")))
    if (const auto* nid = child(it, "FeatureNominalId"))
      if (const auto* nm = child(it, "FeatureName")) item_name[text(nid)] = text(nm);
  const std::string suffix = "FeatureNominal";
  for (const auto* e : children(child(fs, "FeatureNominals"))) {
    const std::string tag = local(e);
    if (tag.size() <= suffix.size() || !tag.ends_with(suffix)) continue;
    CmmFeature f;
    f.kind_name = tag.substr(0, tag.size() - suffix.size());
    f.kind = kindOf(f.kind_name);
    f.line = lineOf(e);
    const auto* nm = child(e, "Name");
    f.name = nm ? text(nm) : item_name.count(attribute(e, "id")) ? item_name[attribute(e, "id")] : "";
    f.nominal = geometryOf(r, e, f.kind);
    if (const auto* def = child(e, "FeatureDefinitionId")) {
      const auto it = defs.find(text(def));
      if (it == defs.end()) r.fail(def, "FeatureDefinitionId: no definition with id " + text(def));
      if (const auto* dia = child(it->second, "Diameter")) f.nominal.diameter_mm = r.lengthOf(dia);
      if (const auto* ie = child(it->second, "InternalExternal")) f.internal = text(ie) == "INTERNAL";
    }
    for (const auto* ref : children(child(e, "PointList"))) {
      const auto it = sets.find(text(ref));
      if (it == sets.end()) r.fail(ref, local(ref) + ": no NominalPointSet with id " + text(ref));
      const auto mps = children(it->second, "MeasurePoint");
      const auto [from, to] = selected(r, ref, mps.size());
      for (std::size_t k = from; k < to; ++k) {
        CmmPoint p;
        const auto* pt = child(mps[k], "Point");
        if (!pt) r.fail(mps[k], "MeasurePoint: no Point");
        p.p_mm = r.position(pt);
        if (const auto* n = child(mps[k], "Normal")) p.normal = r.direction(n);
        f.points.push_back(p);
      }
    }
    d.features.push_back(std::move(f));
  }
  if (d.features.empty()) r.fail(q.root, "no FeatureNominals: not a QIF plan with features to measure");
  return std::move(d);
}

CmmDocument readQifPlan(const std::string& path) { return parseQifPlan(readFile(path), path); }

namespace {

// QIF 3.0 sequences (QIFResults.xsd MeasurementResultsType; Features.xsd
// FeatureMeasurementBaseType, then each kind's geometry): the rank of each element probeloop
// reads; elements of equal rank may stand in any order among themselves.
const std::map<std::string, int> kResultsOrder{
    {"Attributes", 0},       {"InspectionTraceability", 1}, {"ThisResultsInstanceQPId", 2}, {"ExternalFileReferences", 3},
    {"MeasuredFeatures", 4}, {"MeasuredPointSets", 5},      {"MeasuredCharacteristics", 6}, {"ActualTransforms", 7},
    {"InspectionStatus", 9}, {"ActualComponentIds", 10}};
const std::map<std::string, int> kMeasurementOrder{
    {"Attributes", 0}, {"FeatureItemId", 1}, {"FeatureName", 2},  {"TimeStamp", 3},  {"ActualComponentId", 4},
    {"ManufacturingProcessId", 5}, {"MeasurementDeviceIds", 6}, {"ActualTransformId", 7}, {"NotedEventIds", 8},
    {"PointList", 9},  {"SubstituteFeatureAlgorithm", 9}, {"Location", 10},     {"Axis", 10},        {"Normal", 10},    {"Direction", 10},
    {"Diameter", 10},  {"Form", 10}};

// Element order: the XSD fixes it, the meaning does not depend on it (elements are found by name).
void checkOrder(const Reader& r, const xmlNode* parent, const std::map<std::string, int>& order, CmmDocument& d) {
  int highest = -1;
  std::string after;
  for (const auto* c : children(parent)) {
    const auto it = order.find(local(c));
    if (it == order.end() || foreignElement(c)) continue;
    if (it->second < highest)
      r.lenient(c, local(parent) + ": " + local(c) + " stands after " + after + " (QIF 3.0 has it before)", "read as if in order", d);
    if (it->second >= highest) highest = it->second, after = local(c);
  }
}

// Elements in another namespace than QIF's: a producer's extension, whose meaning probeloop
// cannot know and QIF's own elements do not depend on.
void extensions(const Reader& r, const xmlNode* parent, CmmDocument& d) {
  for (const auto* c : children(parent))
    if (foreignElement(c))
      r.lenient(c, local(parent) + ": unknown extension " + local(c) + " (namespace " +
                       reinterpret_cast<const char*>(c->ns->href) + ")", "passed over", d);
}

// A MeasuredPointSet's points (and normals, when given), in mm; InputError for what breaks
// the meaning (count, units, frames, binary points).
std::vector<CmmPoint> setPoints(const Reader& r, const xmlNode* ps) {
  const std::string id = attribute(ps, "id");
  if (child(ps, "BinaryPoints"))
    r.fail(ps, "MeasuredPointSet " + id + ": BinaryPoints (base64) are not read; export the points as text (Points)");
  const auto* pts = child(ps, "Points");
  if (!pts) r.fail(ps, "MeasuredPointSet " + id + ": no Points");
  double count = 0;
  if (!parseFiniteNumber(attribute(ps, "count"), count) || count < 0 || count > kMaxPoints || count != std::floor(count))
    r.fail(ps, "MeasuredPointSet " + id + ": count '" + attribute(ps, "count") + "' is not a whole number from 0 to " +
                   std::to_string(static_cast<long long>(kMaxPoints)));
  if (child(ps, "Units") || child(ps, "CoordinateSystemId") || child(ps, "TranformId"))
    r.fail(ps, "MeasuredPointSet " + id + ": its own Units or coordinate system are not read (export the points in the file's "
                                       "units and frame)");
  const auto n = static_cast<std::size_t>(count);
  const auto xyz = r.numbers(pts, 3 * static_cast<long long>(n));
  std::vector<double> nrm;
  if (const auto* nn = child(ps, "Normals")) nrm = r.numbers(nn, 3 * static_cast<long long>(n));
  const double s = attribute(pts, "linearUnit").empty() ? r.scaleOf(ps) : r.scaleOf(pts);
  std::vector<CmmPoint> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    out[k].p_mm = Eigen::Vector3d(xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]) * s;
    if (!nrm.empty()) {
      const Eigen::Vector3d v(nrm[3 * k], nrm[3 * k + 1], nrm[3 * k + 2]);
      if (v.norm() > 0) out[k].normal = v.normalized();
    }
  }
  return out;
}

// The points a reference selects (ref null: the whole set) appended to the feature.
void appendPoints(const Reader& r, const xmlNode* ps, const xmlNode* ref, CmmFeature& f) {
  const auto pts = setPoints(r, ps);
  const auto [from, to] = ref ? selected(r, ref, pts.size()) : std::make_pair(std::size_t{0}, pts.size());
  f.points.insert(f.points.end(), pts.begin() + static_cast<long>(from), pts.begin() + static_cast<long>(to));
}

// How far a point lies from a feature's measured geometry, mm (NaN: cannot tell).
double offGeometry(const CmmFeature& f, const Eigen::Vector3d& p) {
  const auto& g = f.measured;
  const Eigen::Vector3d v = p - g.location_mm, n = g.direction;
  const double rad = g.diameter_mm / 2;
  const auto radial = [&] { return (v - v.dot(n) * n).norm(); };
  switch (f.kind) {
    case CmmFeatureKind::Point: return v.norm();
    case CmmFeatureKind::Plane: return n.norm() > 0 ? std::abs(v.dot(n)) : NAN;
    case CmmFeatureKind::Sphere: return std::abs(v.norm() - rad);
    case CmmFeatureKind::Line: return n.norm() > 0 ? radial() : NAN;
    case CmmFeatureKind::Cylinder: return n.norm() > 0 ? std::abs(radial() - rad) : NAN;
    case CmmFeatureKind::Circle: return n.norm() > 0 ? std::max(std::abs(v.dot(n)), std::abs(radial() - rad)) : NAN;
    default: return NAN;
  }
}

// A MeasurementResults' point sets: by id, which ones a PointList names, and the unreferenced
// one that fits a feature whose own reference is broken or missing.
struct PointSets {
  std::map<std::string, const xmlNode*> byId;
  std::vector<const xmlNode*> inOrder;
  std::set<std::string> referenced;
  // Parsed once per set (null: unreadable), so that many broken references cost no more than one.
  mutable std::map<const xmlNode*, std::optional<std::vector<CmmPoint>>> parsed;

  // The only unreferenced set whose every point lies on the feature's measured geometry within
  // the set's probe radius (points may be uncompensated tip centres) + 0.05 mm; null when none
  // or several do (fitting: how many).
  const xmlNode* candidate(const Reader& r, const CmmFeature& f, int& fitting) const {
    const xmlNode* found = nullptr;
    fitting = 0;
    if (!f.measured.given) return nullptr;
    for (const auto* ps : inOrder) {
      if (referenced.count(attribute(ps, "id"))) continue;
      if (!parsed.count(ps)) {
        try {
          parsed[ps] = setPoints(r, ps);
        } catch (const InputError&) {  // a set that cannot be read is no candidate
          parsed[ps] = std::nullopt;
        }
      }
      const auto& pts = parsed[ps];
      if (!pts || pts->empty()) continue;
      double tol = 0.05;
      try {
        if (const auto* pr = child(ps, "ProbeRadius")) tol += r.lengthOf(pr);
      } catch (const InputError&) {
        continue;
      }
      bool on = true;
      for (const auto& p : *pts) {
        const double off = offGeometry(f, p.p_mm);
        if (!(std::isfinite(off) && off <= tol)) {
          on = false;
          break;
        }
      }
      if (on) ++fitting, found = ps;
    }
    return fitting == 1 ? found : nullptr;
  }
};

PointSets pointSets(const Reader& r, const xmlNode* mr, CmmDocument& d) {
  PointSets s;
  const auto* group = child(mr, "MeasuredPointSets");
  extensions(r, group, d);
  for (const auto* ps : children(group, "MeasuredPointSet")) {
    s.byId[attribute(ps, "id")] = ps;
    s.inOrder.push_back(ps);
    extensions(r, ps, d);
    ++d.point_sets;
    double count = 0;
    if (parseFiniteNumber(attribute(ps, "count"), count) && count >= 0 && count <= kMaxPoints && count == std::floor(count))
      d.point_set_points += static_cast<std::size_t>(count);
  }
  for (const auto* m : children(child(mr, "MeasuredFeatures")))
    for (const auto* ref : children(child(m, "PointList"))) s.referenced.insert(text(ref));
  return s;
}

}  // namespace

CmmDocument parseQifResults(const std::string& xml, const std::string& file_name, const CmmReadOptions& options) {
  auto q = openQif(xml, file_name, options.strict);
  auto& r = q.r;
  auto& d = q.d;
  const xmlNode* root = q.root;

  // Names by id: feature items (FeatureName) and nominals (Name); characteristic items (Name).
  std::map<std::string, std::string> item_name, nominal_name, item_nominal, char_item_name;
  std::map<std::string, const xmlNode*> nominal_node, definition_node;
  if (const auto* fs = child(root, "Features")) {
    for (const auto* n : children(child(fs, "FeatureDefinitions"))) definition_node[attribute(n, "id")] = n;
    for (const auto* n : children(child(fs, "FeatureNominals"))) {
      nominal_node[attribute(n, "id")] = n;
      if (const auto* nm = child(n, "Name")) nominal_name[attribute(n, "id")] = text(nm);
    }
    for (const auto* it : children(child(fs, "FeatureItems"))) {
      if (const auto* nm = child(it, "FeatureName")) item_name[attribute(it, "id")] = text(nm);
      if (const auto* nid = child(it, "FeatureNominalId")) item_nominal[attribute(it, "id")] = text(nid);
    }
  }
  if (const auto* cs = child(root, "Characteristics"))
    for (const auto* it : children(child(cs, "CharacteristicItems")))
      if (const auto* nm = child(it, "Name")) char_item_name[attribute(it, "id")] = text(nm);

  const auto* results = child(root, "Results");
  const auto* set = child(results, "MeasurementResultsSet");
  int run = 0;
  for (const auto* mr : children(set, "MeasurementResults")) {
    ++run;
    checkOrder(r, mr, kResultsOrder, d);
    extensions(r, mr, d);
    PointSets sets = pointSets(r, mr, d);
    for (const auto* m : children(child(mr, "MeasuredFeatures"))) {
      const std::string tag = local(m);
      if (foreignElement(m)) {
        r.lenient(m, "MeasuredFeatures: unknown extension " + tag + " (namespace " + reinterpret_cast<const char*>(m->ns->href) + ")",
                  "passed over", d);
        continue;
      }
      if (tag.size() <= kMeasurementSuffix.size() || !tag.ends_with(kMeasurementSuffix)) {
        d.notes.push_back("line " + std::to_string(lineOf(m)) + ": " + tag + " passed over (not a feature measurement)");
        continue;
      }
      CmmFeature f;
      f.kind_name = tag.substr(0, tag.size() - kMeasurementSuffix.size());
      f.kind = kindOf(f.kind_name);
      f.line = lineOf(m);
      f.run = run;
      const auto* item = child(m, "FeatureItemId");
      const std::string item_id = item ? text(item) : "";
      if (const auto* nm = child(m, "FeatureName"))
        f.name = text(nm);
      else if (item_name.count(item_id))
        f.name = item_name[item_id];
      else if (item_nominal.count(item_id) && nominal_name.count(item_nominal[item_id]))
        f.name = nominal_name[item_nominal[item_id]];
      else
        f.name = "";
      checkOrder(r, m, kMeasurementOrder, d);
      extensions(r, m, d);
      f.measured = geometryOf(r, m, f.kind);
      // The nominal the measurement's item names, when the file has it.
      if (item_nominal.count(item_id) && nominal_node.count(item_nominal[item_id])) {
        const auto* nn = nominal_node[item_nominal[item_id]];
        f.nominal = geometryOf(r, nn, f.kind);
        if (const auto* def = child(nn, "FeatureDefinitionId"))
          if (definition_node.count(text(def))) {
            const auto* dn = definition_node[text(def)];
            if (const auto* dia = child(dn, "Diameter")) f.nominal.diameter_mm = r.lengthOf(dia);
            if (const auto* ie = child(dn, "InternalExternal")) f.internal = text(ie) == "INTERNAL";
          }
      }
      const auto* list = child(m, "PointList");
      for (const auto* ref : children(list)) {
        const std::string rt = local(ref), id = text(ref);
        if (rt != "WholePointSetId" && rt != "RangePointSetId" && rt != "SinglePointSetId")
          r.fail(ref, "PointList: " + rt + " is not a point-set reference probeloop knows");
        auto it = sets.byId.find(id);
        if (it == sets.byId.end()) {
          // A dangling or self-referencing id (CheckMate: a point feature naming its own id).
          const std::string problem = rt + ": no MeasuredPointSet with id " + id + " in this MeasurementResults" +
                                      (id == attribute(m, "id") ? " (it is the feature measurement's own id)" : "");
          int fitting = 0;
          const auto* cand = sets.candidate(r, f, fitting);
          r.lenient(ref, problem, cand ? "assigned MeasuredPointSet " + attribute(cand, "id") +
                                             ", the only unreferenced set on the feature's measured geometry"
                                       : "the feature's points left unassigned (" + std::to_string(fitting) +
                                             " unreferenced sets lie on its measured geometry)", d);
          if (!cand) continue;
          sets.referenced.insert(attribute(cand, "id"));
          appendPoints(r, cand, nullptr, f);
          continue;
        }
        appendPoints(r, it->second, ref, f);
      }
      int fitting = 0;
      if (!list && f.measured.given)
        if (const auto* cand = sets.candidate(r, f, fitting)) {  // a missing optional block with its data present
          r.lenient(m, f.kind_name + "FeatureMeasurement " + attribute(m, "id") + " has no PointList, but MeasuredPointSet " +
                           attribute(cand, "id") + " (referenced by no feature) lies on its measured geometry",
                    "assigned it", d);
          sets.referenced.insert(attribute(cand, "id"));
          appendPoints(r, cand, nullptr, f);
        }
      d.features.push_back(std::move(f));
    }
    if (const auto* mc = child(mr, "MeasuredCharacteristics")) {
      // A measurement with only its status (Value is optional in QIF): nothing to read; counted
      // in a note, so that a converter that lost values says so.
      std::vector<std::string> without_value;
      for (const auto* c : children(child(mc, "CharacteristicMeasurements"))) {
        const auto* v = child(c, "Value");
        const auto* item = child(c, "CharacteristicItemId");
        const std::string name = item && char_item_name.count(text(item)) ? char_item_name[text(item)] : local(c);
        if (!v) {
          without_value.push_back(name);
          continue;
        }
        CmmCharacteristic ch;
        ch.name = name;
        // Angles: the user-defined angular and the angle types (not Angularity, a zone in length).
        const std::string t = local(c);
        ch.angular = t.rfind("UserDefinedAngular", 0) == 0 || t.rfind("Angle", 0) == 0 || t.rfind("AngularCoordinate", 0) == 0;
        const double scale = ch.angular ? r.radPer(v) : r.scaleOf(v);
        ch.value = r.numbers(v, 1)[0] * scale;
        double u = 0;
        if (parseFiniteNumber(attribute(v, "combinedUncertainty"), u)) ch.u = u * scale;
        d.characteristics.push_back(ch);
      }
      if (!without_value.empty()) {
        std::string names;
        for (std::size_t i = 0; i < without_value.size() && i < 6; ++i) names += (i ? ", " : "") + without_value[i];
        d.notes.push_back(std::to_string(without_value.size()) + " characteristic measurement" + (without_value.size() > 1 ? "s" : "") +
                          " without a Value (" + names + (without_value.size() > 6 ? ", ..." : "") + "): a status only, not read");
      }
    }
  }
  d.runs = run;
  return d;
}

CmmDocument readQifResults(const std::string& path, const CmmReadOptions& options) {
  return parseQifResults(readFile(path), path, options);
}

}  // namespace probeloop::interop
