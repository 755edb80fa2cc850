#include "interop/qif.hpp"

#include <libxml/parser.h>
#include <libxml/tree.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::interop {

const char* cmmFeatureKindName(CmmFeatureKind k) {
  switch (k) {
    case CmmFeatureKind::Plane: return "plane";
    case CmmFeatureKind::Sphere: return "sphere";
    case CmmFeatureKind::Cylinder: return "cylinder";
    case CmmFeatureKind::Circle: return "circle";
    case CmmFeatureKind::Point: return "point";
    case CmmFeatureKind::Line: return "line";
    case CmmFeatureKind::Other: return "other";
  }
  return "other";
}

namespace {

constexpr const char* kNamespace = "http://qifstandards.org/xsd/qif3";

// ---------------------------------------------------------------------------------------------
// Writing

// Fixed notation (xs:decimal takes no exponent), trailing zeros dropped, no "-0".
std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) throw std::logic_error("QIF: a value to write is not finite");
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  if (s.find('.') != std::string::npos) {
    while (!s.empty() && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}
std::string length(double mm) { return fixed(mm, 6); }
std::string vec(const Eigen::Vector3d& v, int decimals) {
  return fixed(v.x(), decimals) + " " + fixed(v.y(), decimals) + " " + fixed(v.z(), decimals);
}
std::string point(const Eigen::Vector3d& p) { return vec(p, 6); }
std::string unit(const Eigen::Vector3d& d) { return vec(d, 9); }

// A UUID-shaped QPId from the content (FNV-1a, two seeds): the same document, the same id.
std::string qpidOf(const std::string& content) {
  auto fnv = [&](std::uint64_t h) {
    for (unsigned char c : content) {
      h ^= c;
      h *= 1099511628211ULL;
    }
    return h;
  };
  const std::uint64_t a = fnv(1469598103934665603ULL), b = fnv(0x9e3779b97f4a7c15ULL);
  char buf[40];
  std::snprintf(buf, sizeof buf, "%08x-%04x-4%03x-8%03x-%012llx", static_cast<unsigned>(a >> 32),
                static_cast<unsigned>((a >> 16) & 0xffff), static_cast<unsigned>(a & 0xfff), static_cast<unsigned>((b >> 48) & 0xfff),
                static_cast<unsigned long long>(b & 0xffffffffffffULL));
  return buf;
}

const char* qifKind(CmmFeatureKind k) {
  switch (k) {
    case CmmFeatureKind::Plane: return "Plane";
    case CmmFeatureKind::Sphere: return "Sphere";
    case CmmFeatureKind::Cylinder: return "Cylinder";
    default: throw std::logic_error(std::string("QIF writer: a ") + cmmFeatureKindName(k) + " feature is not written");
  }
}

struct DocDeleter {
  void operator()(xmlDoc* d) const { xmlFreeDoc(d); }
};
using DocPtr = std::unique_ptr<xmlDoc, DocDeleter>;

class Writer {
 public:
  Writer() : doc_(xmlNewDoc(BAD_CAST "1.0")) {
    root_ = xmlNewDocNode(doc_.get(), nullptr, BAD_CAST "QIFDocument", nullptr);
    ns_ = xmlNewNs(root_, BAD_CAST kNamespace, nullptr);
    xmlSetNs(root_, ns_);
    xmlDocSetRootElement(doc_.get(), root_);
  }
  xmlNodePtr root() { return root_; }
  xmlNodePtr add(xmlNodePtr parent, const char* name, const std::string& text = {}) {
    return xmlNewTextChild(parent, ns_, BAD_CAST name, text.empty() ? nullptr : BAD_CAST text.c_str());
  }
  static void attr(xmlNodePtr n, const char* name, const std::string& v) { xmlNewProp(n, BAD_CAST name, BAD_CAST v.c_str()); }
  int id(xmlNodePtr n) {
    const int i = next_++;
    attr(n, "id", std::to_string(i));
    return i;
  }
  int reserve() { return next_++; }
  static void setId(xmlNodePtr n, int i) { attr(n, "id", std::to_string(i)); }
  xmlNodePtr list(xmlNodePtr parent, const char* name, std::size_t n) {
    auto* l = add(parent, name);
    attr(l, "n", std::to_string(n));
    return l;
  }
  std::string finish() {
    xmlNewProp(root_, BAD_CAST "versionQIF", BAD_CAST "3.0.0");
    xmlNewProp(root_, BAD_CAST "idMax", BAD_CAST std::to_string(next_ - 1).c_str());
    xmlChar* mem = nullptr;
    int size = 0;
    xmlDocDumpFormatMemoryEnc(doc_.get(), &mem, &size, "UTF-8", 1);
    std::string out(reinterpret_cast<const char*>(mem), static_cast<std::size_t>(size));
    xmlFree(mem);
    return out;
  }

 private:
  DocPtr doc_;
  xmlNodePtr root_ = nullptr;
  xmlNsPtr ns_ = nullptr;
  int next_ = 1;
};

std::string contentKey(const CmmDocument& d, const char* what) {
  std::ostringstream k;
  k << what << '|' << d.part_name;
  auto geometry = [&](const CmmGeometry& g) {
    if (!g.given) return;
    k << ',' << point(g.location_mm) << ',' << unit(g.direction);
    if (std::isfinite(g.diameter_mm)) k << ',' << length(g.diameter_mm);
    if (std::isfinite(g.form_mm)) k << ',' << length(g.form_mm);
  };
  for (const auto& f : d.features) {
    k << '|' << f.name << ',' << cmmFeatureKindName(f.kind) << ',' << f.internal;
    geometry(f.nominal);
    geometry(f.measured);
    for (const auto& p : f.points) k << ';' << point(p.p_mm) << ',' << unit(p.normal);
  }
  for (const auto& c : d.characteristics)
    k << '|' << c.name << ',' << fixed(c.value, 12) << ',' << (std::isfinite(c.u) ? fixed(c.u, 12) : "-");
  return k.str();
}

void fileUnits(Writer& w, bool angular) {
  auto* pu = w.add(w.add(w.root(), "FileUnits"), "PrimaryUnits");
  if (angular) w.add(w.add(pu, "AngularUnit"), "UnitName", "radian");
  w.add(w.add(pu, "LinearUnit"), "UnitName", "mm");
}

struct FeatureIds {
  int item = 0, point_set = 0;
};

// The Features section: definitions, nominals, items and (plan) the planned points.
std::vector<FeatureIds> features(Writer& w, const CmmDocument& d, bool planned_points) {
  const std::size_t n = d.features.size();
  std::vector<int> def(n), nom(n);
  std::vector<FeatureIds> ids(n);
  if (n == 0) return ids;  // the XSD wants every list with n >= 1: no Features section
  for (std::size_t i = 0; i < n; ++i) def[i] = w.reserve();
  for (std::size_t i = 0; i < n; ++i) nom[i] = w.reserve();
  for (std::size_t i = 0; i < n; ++i) ids[i].item = w.reserve();
  if (planned_points)
    for (std::size_t i = 0; i < n; ++i) ids[i].point_set = w.reserve();
  auto* fs = w.add(w.root(), "Features");
  auto* defs = w.list(fs, "FeatureDefinitions", n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& f = d.features[i];
    auto* e = w.add(defs, (std::string(qifKind(f.kind)) + "FeatureDefinition").c_str());
    Writer::setId(e, def[i]);
    if (f.kind != CmmFeatureKind::Plane) {
      w.add(e, "InternalExternal", f.internal ? "INTERNAL" : "EXTERNAL");
      if (!std::isfinite(f.nominal.diameter_mm)) throw std::logic_error("QIF writer: feature " + f.name + " has no diameter");
      w.add(e, "Diameter", length(f.nominal.diameter_mm));
    }
  }
  auto* noms = w.list(fs, "FeatureNominals", n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& f = d.features[i];
    auto* e = w.add(noms, (std::string(qifKind(f.kind)) + "FeatureNominal").c_str());
    Writer::setId(e, nom[i]);
    w.add(e, "Name", f.name);
    w.add(e, "FeatureDefinitionId", std::to_string(def[i]));
    if (planned_points && !f.points.empty()) w.add(w.list(e, "PointList", 1), "WholePointSetId", std::to_string(ids[i].point_set));
    if (f.kind == CmmFeatureKind::Cylinder) {
      auto* ax = w.add(e, "Axis");
      w.add(ax, "AxisPoint", point(f.nominal.location_mm));
      w.add(ax, "Direction", unit(f.nominal.direction));
    } else {
      w.add(e, "Location", point(f.nominal.location_mm));
      if (f.kind == CmmFeatureKind::Plane) w.add(e, "Normal", unit(f.nominal.direction));
    }
  }
  auto* items = w.list(fs, "FeatureItems", n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& f = d.features[i];
    auto* e = w.add(items, (std::string(qifKind(f.kind)) + "FeatureItem").c_str());
    Writer::setId(e, ids[i].item);
    w.add(e, "FeatureNominalId", std::to_string(nom[i]));
    w.add(e, "FeatureName", f.name);
    w.add(w.add(e, "DeterminationMode"), "Checked");
  }
  // A feature without planned points has no set (the XSD wants n >= 1 in every list).
  const std::size_t with_points =
      static_cast<std::size_t>(std::count_if(d.features.begin(), d.features.end(), [](const CmmFeature& f) { return !f.points.empty(); }));
  if (planned_points && with_points > 0) {
    auto* sets = w.list(fs, "NominalPointSets", with_points);
    for (std::size_t i = 0; i < n; ++i) {
      const auto& f = d.features[i];
      if (f.points.empty()) continue;
      auto* s = w.add(sets, "NominalPointSet");
      Writer::setId(s, ids[i].point_set);
      Writer::attr(s, "n", std::to_string(f.points.size()));
      for (const auto& p : f.points) {
        auto* mp = w.add(s, "MeasurePoint");
        w.id(mp);
        w.add(mp, "Point", point(p.p_mm));
        if (p.normal.squaredNorm() > 0) w.add(mp, "Normal", unit(p.normal));
      }
    }
  }
  return ids;
}

struct CharacteristicIds {
  int item = 0;
};

std::vector<CharacteristicIds> characteristics(Writer& w, const CmmDocument& d, int standard_id) {
  std::vector<CharacteristicIds> ids(d.characteristics.size());
  if (d.characteristics.empty()) return ids;
  auto* cs = w.add(w.root(), "Characteristics");
  w.add(cs, "FormalStandardId", std::to_string(standard_id));
  const auto type = [](const CmmCharacteristic& c) { return std::string(c.angular ? "UserDefinedAngular" : "UserDefinedLinear"); };
  std::vector<int> def, nom;
  auto* defs = w.list(cs, "CharacteristicDefinitions", d.characteristics.size());
  for (const auto& c : d.characteristics) {
    auto* e = w.add(defs, (type(c) + "CharacteristicDefinition").c_str());
    def.push_back(w.id(e));
    w.add(e, "Name", c.name);
    w.add(e, "NonTolerance", "MEASURED");
    w.add(e, "WhatToMeasure", c.name);
  }
  auto* noms = w.list(cs, "CharacteristicNominals", d.characteristics.size());
  for (std::size_t i = 0; i < d.characteristics.size(); ++i) {
    const auto& c = d.characteristics[i];
    auto* e = w.add(noms, (type(c) + "CharacteristicNominal").c_str());
    nom.push_back(w.id(e));
    w.add(e, "CharacteristicDefinitionId", std::to_string(def[i]));
    w.add(e, "Name", c.name);
    w.add(e, "TargetValue", "0");
  }
  auto* items = w.list(cs, "CharacteristicItems", d.characteristics.size());
  for (std::size_t i = 0; i < d.characteristics.size(); ++i) {
    const auto& c = d.characteristics[i];
    auto* e = w.add(items, (type(c) + "CharacteristicItem").c_str());
    ids[i].item = w.id(e);
    w.add(e, "Name", c.name);
    w.add(e, "CharacteristicNominalId", std::to_string(nom[i]));
  }
  return ids;
}

int standards(Writer& w) {
  auto* s = w.add(w.list(w.root(), "StandardsDefinitions", 1), "Standard");
  const int id = w.id(s);
  w.add(w.add(s, "Organization"), "StandardsOrganizationEnum", "ISO");
  w.add(s, "Designator", "23952");
  return id;
}

}  // namespace

std::string qifPlan(const CmmDocument& plan) {
  Writer w;
  w.add(w.root(), "QPId", qpidOf(contentKey(plan, "plan")));
  fileUnits(w, false);
  const auto ids = features(w, plan, true);
  auto* steps = w.list(w.add(w.add(w.root(), "Plan"), "OrderedPlanRoot"), "Steps", ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    auto* e = w.add(steps, "NumberedPlanElement");
    w.add(e, "SequenceNumber", std::to_string(i + 1));
    w.add(w.list(w.add(e, "MeasureSpecifiedFeatures"), "FeatureItemIds", 1), "Id", std::to_string(ids[i].item));
  }
  return w.finish();
}

std::string qifResults(const CmmDocument& results) {
  Writer w;
  w.add(w.root(), "QPId", qpidOf(contentKey(results, "results")));
  bool angular = false;
  for (const auto& c : results.characteristics) angular = angular || c.angular;
  const int standard = results.characteristics.empty() ? 0 : standards(w);
  fileUnits(w, angular);
  const auto fids = features(w, results, false);
  const auto cids = characteristics(w, results, standard);
  auto* mr = w.add(w.list(w.add(w.root(), "Results"), "MeasurementResultsSet", 1), "MeasurementResults");
  w.id(mr);
  const std::size_t n = results.features.size();
  std::vector<int> set_id(n);
  auto* mf = n ? w.list(mr, "MeasuredFeatures", n) : nullptr;
  std::vector<xmlNodePtr> measured(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& f = results.features[i];
    measured[i] = w.add(mf, (std::string(qifKind(f.kind)) + "FeatureMeasurement").c_str());
    w.id(measured[i]);
  }
  for (std::size_t i = 0; i < n; ++i) set_id[i] = w.reserve();
  for (std::size_t i = 0; i < n; ++i) {
    const auto& f = results.features[i];
    auto* e = measured[i];
    w.add(e, "FeatureItemId", std::to_string(fids[i].item));
    if (!f.points.empty()) w.add(w.list(e, "PointList", 1), "WholePointSetId", std::to_string(set_id[i]));
    const auto& g = f.measured;
    if (!g.given) continue;
    if (f.kind == CmmFeatureKind::Cylinder) {
      auto* ax = w.add(e, "Axis");
      w.add(ax, "AxisPoint", point(g.location_mm));
      w.add(ax, "Direction", unit(g.direction));
      w.add(e, "Diameter", length(g.diameter_mm));
    } else {
      w.add(e, "Location", point(g.location_mm));
      if (f.kind == CmmFeatureKind::Plane) w.add(e, "Normal", unit(g.direction));
      if (f.kind == CmmFeatureKind::Sphere) w.add(e, "Diameter", length(g.diameter_mm));
    }
    if (std::isfinite(g.form_mm)) w.add(e, "Form", length(g.form_mm));
  }
  const std::size_t with_points = static_cast<std::size_t>(
      std::count_if(results.features.begin(), results.features.end(), [](const CmmFeature& f) { return !f.points.empty(); }));
  auto* sets = with_points ? w.list(mr, "MeasuredPointSets", with_points) : nullptr;
  for (std::size_t i = 0; i < n; ++i) {
    const auto& f = results.features[i];
    if (f.points.empty()) continue;
    auto* s = w.add(sets, "MeasuredPointSet");
    Writer::setId(s, set_id[i]);
    Writer::attr(s, "count", std::to_string(f.points.size()));
    std::string pts, nrm;
    bool normals = !f.points.empty();
    for (const auto& p : f.points) {
      pts += (pts.empty() ? "" : " ") + point(p.p_mm);
      normals = normals && p.normal.squaredNorm() > 0;
    }
    if (normals)
      for (const auto& p : f.points) nrm += (nrm.empty() ? "" : " ") + unit(p.normal);
    w.add(s, "Points", pts);
    if (normals) w.add(s, "Normals", nrm);
    w.add(s, "Compensated", "true");
  }
  if (!results.characteristics.empty()) {
    auto* cm = w.list(w.add(mr, "MeasuredCharacteristics"), "CharacteristicMeasurements", results.characteristics.size());
    for (std::size_t i = 0; i < results.characteristics.size(); ++i) {
      const auto& c = results.characteristics[i];
      auto* e = w.add(cm, (std::string(c.angular ? "UserDefinedAngular" : "UserDefinedLinear") + "CharacteristicMeasurement").c_str());
      w.id(e);
      w.add(w.add(e, "Status"), "CharacteristicStatusEnum", "NOT_ANALYZED");
      w.add(e, "CharacteristicItemId", std::to_string(cids[i].item));
      // 1e-9 mm, 1e-12 rad: below the printed digits of errors.csv (um, urad to 3 decimals)
      const int digits = c.angular ? 12 : 9;
      auto* v = w.add(e, "Value", fixed(c.value, digits));
      if (std::isfinite(c.u)) {  // the XSD: both attributes or neither
        Writer::attr(v, "combinedUncertainty", fixed(c.u, digits));
        Writer::attr(v, "meanError", "0");
      }
    }
  }
  w.add(w.add(mr, "InspectionStatus"), "InspectionStatusEnum", "NOT_CALCULATED");
  return w.finish();
}

// ---------------------------------------------------------------------------------------------
// Reading

namespace {

std::string local(const xmlNode* n) { return reinterpret_cast<const char*>(n->name); }

std::vector<xmlNodePtr> children(const xmlNode* n, const char* name = nullptr) {
  std::vector<xmlNodePtr> out;
  for (xmlNodePtr c = n ? n->children : nullptr; c; c = c->next)
    if (c->type == XML_ELEMENT_NODE && (!name || local(c) == name)) out.push_back(c);
  return out;
}
xmlNodePtr child(const xmlNode* n, const char* name) {
  for (xmlNodePtr c = n ? n->children : nullptr; c; c = c->next)
    if (c->type == XML_ELEMENT_NODE && local(c) == name) return c;
  return nullptr;
}
std::string text(const xmlNode* n) {
  xmlChar* t = xmlNodeGetContent(n);
  std::string s = t ? reinterpret_cast<const char*>(t) : "";
  xmlFree(t);
  const auto a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}
std::string attribute(const xmlNode* n, const char* name) {
  xmlChar* v = xmlGetProp(n, BAD_CAST name);
  std::string s = v ? reinterpret_cast<const char*>(v) : "";
  xmlFree(v);
  return s;
}
int lineOf(const xmlNode* n) { return static_cast<int>(xmlGetLineNo(n)); }

class Reader {
 public:
  Reader(const std::string& file) : file_(file) {}

  [[noreturn]] void fail(const xmlNode* n, const std::string& what) const { throw InputError(file_, n ? lineOf(n) : 0, what); }

  // expected < 0: any number of values.
  std::vector<double> numbers(const xmlNode* n, long long expected = -1) const {
    std::vector<double> v;
    std::istringstream ss(text(n));
    for (std::string tok; ss >> tok;) {
      double x = 0;
      // xs:double allows INF/NaN; a coordinate must be finite.
      if (!parseFiniteNumber(tok, x)) fail(n, local(n) + ": '" + tok + "' is not a finite number");
      v.push_back(x);
    }
    if (expected >= 0 && v.size() != static_cast<std::size_t>(expected))
      fail(n, local(n) + ": " + std::to_string(v.size()) + " numbers, expected " + std::to_string(expected));
    return v;
  }

  // mm per unit of a length unit name or conversion factor (to metres).
  double mmPer(const xmlNode* unit_node) const {
    if (const auto* conv = child(unit_node, "UnitConversion"))
      if (const auto* f = child(conv, "Factor")) {
        const auto v = numbers(f, 1);
        if (!(v[0] > 0)) fail(f, "Factor: must be positive");
        return v[0] * 1000.0;
      }
    const auto* nm = child(unit_node, "UnitName");
    const std::string name = nm ? text(nm) : "";
    static const std::map<std::string, double> known{{"mm", 1},       {"millimeter", 1}, {"millimetre", 1}, {"m", 1000},
                                                     {"meter", 1000}, {"metre", 1000},   {"cm", 10},        {"um", 1e-3},
                                                     {"micron", 1e-3}, {"inch", 25.4},   {"in", 25.4},      {"ft", 304.8},
                                                     {"foot", 304.8}, {"mil", 0.0254},   {"uin", 2.54e-5},  {"km", 1e6},
                                                     {"mi", 1609344}};
    const auto it = known.find(name);
    if (it == known.end()) fail(nm ? nm : unit_node, "UnitName: '" + name + "' is not a length unit probeloop knows, and no UnitConversion/Factor is given");
    return it->second;
  }

  void units(const xmlNode* root, CmmDocument& d) {
    const auto* fu = child(root, "FileUnits");
    if (!fu) {
      d.notes.push_back("no FileUnits: lengths read in mm");
      return;
    }
    if (const auto* pu = child(fu, "PrimaryUnits"))
      if (const auto* lu = child(pu, "LinearUnit")) {
        scale_ = mmPer(lu);
        if (const auto* nm = child(lu, "UnitName")) d.length_unit = text(nm);
      }
    if (const auto* pu = child(fu, "PrimaryUnits"))
      for (const char* a : {"AngularUnit", "PMIAngularUnit"})
        if (const auto* au = child(pu, a)) {
          angle_scale_ = angleFactor(au);
          break;
        }
    for (const auto* group : {child(fu, "PrimaryUnits"), child(fu, "OtherUnits")})
      for (const auto* u : children(group))
        if (local(u) == "AngularUnit" || local(u) == "PMIAngularUnit")
          if (const auto* nm = child(u, "UnitName")) angular_named_[text(nm)] = u;
    // Units an element may name by its linearUnit attribute.
    for (const auto* group : {child(fu, "PrimaryUnits"), child(fu, "OtherUnits")})
      for (const auto* u : children(group))
        if (local(u) == "LinearUnit" || local(u) == "PMILinearUnit")
          if (const auto* nm = child(u, "UnitName")) named_[text(nm)] = u;
  }

  // rad per unit of the file's angle unit (degree when named so; radian otherwise), or of the
  // element's angularUnit attribute.
  double radPer(const xmlNode* n) const {
    const std::string u = attribute(n, "angularUnit");
    if (!u.empty()) {
      const auto it = angular_named_.find(u);
      if (it == angular_named_.end()) fail(n, "angularUnit '" + u + "' is not declared in FileUnits");
      return angleFactor(it->second);
    }
    return angle_scale_;
  }
  double angleFactor(const xmlNode* unit_node) const {
    if (const auto* conv = child(unit_node, "UnitConversion"))
      if (const auto* f = child(conv, "Factor")) return numbers(f, 1)[0];  // to radians
    const auto* nm = child(unit_node, "UnitName");
    const std::string name = nm ? text(nm) : "";
    if (name == "degree" || name == "degrees" || name == "deg") return M_PI / 180;
    if (name == "radian" || name == "radians" || name == "rad") return 1.0;
    fail(nm ? nm : unit_node, "UnitName: '" + name + "' is not an angle unit probeloop knows, and no UnitConversion/Factor is given");
  }

  double scaleOf(const xmlNode* n) const {
    const std::string u = attribute(n, "linearUnit");
    if (u.empty()) return scale_;
    const auto it = named_.find(u);
    if (it == named_.end()) fail(n, "linearUnit '" + u + "' is not declared in FileUnits");
    return mmPer(it->second);
  }
  Eigen::Vector3d position(const xmlNode* n) const {
    const auto v = numbers(n, 3);
    return Eigen::Vector3d(v[0], v[1], v[2]) * scaleOf(n);
  }
  Eigen::Vector3d direction(const xmlNode* n) const {
    const auto v = numbers(n, 3);
    const Eigen::Vector3d d(v[0], v[1], v[2]);
    if (!(d.norm() > 0)) fail(n, local(n) + ": a zero direction");
    return d.normalized();
  }
  double lengthOf(const xmlNode* n) const { return numbers(n, 1)[0] * scaleOf(n); }

  std::string file_;
  double scale_ = 1.0, angle_scale_ = 1.0;
  std::map<std::string, const xmlNode*> named_, angular_named_;
};

CmmFeatureKind kindOf(const std::string& qif) {
  if (qif == "Plane") return CmmFeatureKind::Plane;
  if (qif == "Sphere") return CmmFeatureKind::Sphere;
  if (qif == "Cylinder") return CmmFeatureKind::Cylinder;
  if (qif == "Circle") return CmmFeatureKind::Circle;
  if (qif == "Point" || qif == "EdgePoint") return CmmFeatureKind::Point;
  if (qif == "Line") return CmmFeatureKind::Line;
  return CmmFeatureKind::Other;
}

// The geometry a feature nominal or measurement carries, by kind (all of it optional).
CmmGeometry geometryOf(const Reader& r, const xmlNode* e, CmmFeatureKind kind) {
  CmmGeometry g;
  if (kind == CmmFeatureKind::Cylinder) {
    const auto* ax = child(e, "Axis");
    if (ax && child(ax, "AxisPoint") && child(ax, "Direction")) {
      g.location_mm = r.position(child(ax, "AxisPoint"));
      g.direction = r.direction(child(ax, "Direction"));
      g.given = true;
    }
  } else if (kind != CmmFeatureKind::Other) {
    if (const auto* loc = child(e, "Location")) {
      g.location_mm = r.position(loc);
      g.given = true;
      if (const auto* dn = child(e, kind == CmmFeatureKind::Line ? "Direction" : "Normal")) g.direction = r.direction(dn);
    }
  }
  if (const auto* dia = child(e, "Diameter")) g.diameter_mm = r.lengthOf(dia);
  if (const auto* form = child(e, "Form")) g.form_mm = r.lengthOf(form);
  return g;
}

const std::string kMeasurementSuffix = "FeatureMeasurement";
constexpr double kMaxPoints = 1e8;  // per point set: a bound, so that 3 x count cannot overflow

}  // namespace

bool looksLikeQif(const std::string& text) {
  // The first element after the BOM, the XML declaration, comments and processing
  // instructions: QIFDocument, with or without a namespace prefix.
  std::size_t p = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
  while (true) {
    p = text.find_first_not_of(" \t\r\n", p);
    if (p == std::string::npos || text[p] != '<') return false;
    if (text.compare(p, 4, "<!--") == 0) {
      p = text.find("-->", p);
      if (p == std::string::npos) return false;
      p += 3;
    } else if (text.compare(p, 2, "<?") == 0 || text.compare(p, 2, "<!") == 0) {
      // A DOCTYPE's internal subset ([ ... ]) holds '>' of its own declarations.
      const std::size_t gt = text.find('>', p), bracket = text.find('[', p);
      if (text.compare(p, 9, "<!DOCTYPE") == 0 && bracket != std::string::npos && bracket < gt) {
        p = text.find("]", bracket);
        if (p == std::string::npos) return false;
      }
      p = text.find('>', p);
      if (p == std::string::npos) return false;
      ++p;
    } else {
      const auto end = text.find_first_of(" \t\r\n/>", p);
      const std::string name = text.substr(p + 1, end == std::string::npos ? std::string::npos : end - p - 1);
      const auto colon = name.find(':');
      return (colon == std::string::npos ? name : name.substr(colon + 1)) == "QIFDocument";
    }
  }
}

namespace {

struct OpenedQif {
  DocPtr doc;
  Reader r;
  const xmlNode* root = nullptr;
  CmmDocument d;
};

// Parses, checks the root, namespace and version, reads the units.
OpenedQif openQif(const std::string& xml, const std::string& file_name) {
  xmlDocPtr raw = xmlReadMemory(xml.data(), static_cast<int>(xml.size()), file_name.c_str(), nullptr,
                                XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING | XML_PARSE_HUGE | XML_PARSE_BIG_LINES);
  if (!raw) {
    const xmlError* e = xmlGetLastError();
    throw InputError(file_name, e ? e->line : 0,
                     std::string("not well-formed XML: ") + (e && e->message ? e->message : "unreadable"));
  }
  OpenedQif q{DocPtr(raw), Reader(file_name), nullptr, {}};
  // Entities are not expanded by the parser but would be by xmlNodeGetContent (an exponential
  // "billion laughs"): QIF needs no DTD, so a document with one is refused.
  if (q.doc->intSubset || q.doc->extSubset) {
    const auto at = xml.find("<!DOCTYPE");
    const int line = at == std::string::npos ? 0 : 1 + static_cast<int>(std::count(xml.begin(), xml.begin() + static_cast<long>(at), '\n'));
    throw InputError(file_name, line, "a DOCTYPE (DTD or entity declarations): QIF documents have none; not read");
  }
  const xmlNode* root = xmlDocGetRootElement(q.doc.get());
  q.root = root;
  auto& r = q.r;
  if (!root || local(root) != "QIFDocument")
    r.fail(root, "the root element is " + (root ? local(root) : std::string("missing")) + ", not QIFDocument: not a QIF file");
  const std::string ns = root->ns && root->ns->href ? reinterpret_cast<const char*>(root->ns->href) : "";
  if (ns != kNamespace)
    r.fail(root, "QIFDocument: namespace '" + ns + "'; probeloop reads QIF 3 (" + kNamespace + ", ISO 23952:2020)");
  const std::string version = attribute(root, "versionQIF");
  if (version.rfind("3.", 0) != 0)
    r.fail(root, "versionQIF: '" + version + "'; probeloop reads QIF 3.0 (ISO 23952:2020)");
  q.d.file = file_name;
  if (version != "3.0.0") q.d.notes.push_back("versionQIF " + version + " read as 3.0.0");
  r.units(root, q.d);
  // Product geometry (a CAD model's vertices) is not measurement data: said, not read.
  if (const auto* gs = child(child(root, "Product"), "GeometrySet"))
    for (const auto* ps : children(gs, "PointSet"))
      q.d.notes.push_back("line " + std::to_string(lineOf(ps)) + ": Product/GeometrySet/PointSet of " +
                          std::to_string(children(ps, "Point").size()) + " CAD points (product geometry, not measurements) passed over");
  return q;
}

// The [from, to) range of a point set of n points that a PointList reference selects.
std::pair<std::size_t, std::size_t> selected(const Reader& r, const xmlNode* ref, std::size_t n) {
  const std::string rt = local(ref);
  if (rt == "WholePointSetId") return {0, n};
  if (rt == "RangePointSetId") {
    std::istringstream rs(attribute(ref, "range"));
    long a = 0, b = 0;
    std::string extra;
    if (!(rs >> a >> b) || (rs >> extra) || a < 1 || b < a || static_cast<std::size_t>(b) > n)
      r.fail(ref, "RangePointSetId: range '" + attribute(ref, "range") + "' is not within 1.." + std::to_string(n));
    return {static_cast<std::size_t>(a - 1), static_cast<std::size_t>(b)};
  }
  if (rt == "SinglePointSetId") {
    double k = 0;
    if (!parseFiniteNumber(attribute(ref, "index"), k) || k < 1 || k > static_cast<double>(n) || k != std::floor(k))
      r.fail(ref, "SinglePointSetId: index '" + attribute(ref, "index") + "' is not within 1.." + std::to_string(n));
    return {static_cast<std::size_t>(k - 1), static_cast<std::size_t>(k)};
  }
  r.fail(ref, "PointList: " + rt + " is not a point-set reference probeloop knows");
}

}  // namespace

CmmDocument parseQifPlan(const std::string& xml, const std::string& file_name) {
  auto q = openQif(xml, file_name);
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

CmmDocument parseQifResults(const std::string& xml, const std::string& file_name) {
  auto q = openQif(xml, file_name);
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
    std::map<std::string, const xmlNode*> point_sets;
    for (const auto* ps : children(child(mr, "MeasuredPointSets"), "MeasuredPointSet")) point_sets[attribute(ps, "id")] = ps;
    for (const auto* m : children(child(mr, "MeasuredFeatures"))) {
      const std::string tag = local(m);
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
      for (const auto* ref : children(child(m, "PointList"))) {
        const std::string rt = local(ref), id = text(ref);
        if (rt != "WholePointSetId" && rt != "RangePointSetId" && rt != "SinglePointSetId")
          r.fail(ref, "PointList: " + rt + " is not a point-set reference probeloop knows");
        const auto it = point_sets.find(id);
        if (it == point_sets.end()) r.fail(ref, rt + ": no MeasuredPointSet with id " + id + " in this MeasurementResults");
        const auto* ps = it->second;
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
        const auto [from, to] = selected(r, ref, n);
        for (std::size_t k = from; k < to; ++k) {
          CmmPoint p;
          p.p_mm = Eigen::Vector3d(xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]) * s;
          if (!nrm.empty()) {
            const Eigen::Vector3d v(nrm[3 * k], nrm[3 * k + 1], nrm[3 * k + 2]);
            if (v.norm() > 0) p.normal = v.normalized();
          }
          f.points.push_back(p);
        }
      }
      d.features.push_back(std::move(f));
    }
    if (const auto* mc = child(mr, "MeasuredCharacteristics"))
      for (const auto* c : children(child(mc, "CharacteristicMeasurements"))) {
        const auto* v = child(c, "Value");
        if (!v) continue;
        CmmCharacteristic ch;
        const auto* item = child(c, "CharacteristicItemId");
        ch.name = item && char_item_name.count(text(item)) ? char_item_name[text(item)] : local(c);
        // Angles: the user-defined angular and the angle types (not Angularity, a zone in length).
        const std::string t = local(c);
        ch.angular = t.rfind("UserDefinedAngular", 0) == 0 || t.rfind("Angle", 0) == 0 || t.rfind("AngularCoordinate", 0) == 0;
        const double scale = ch.angular ? r.radPer(v) : r.scaleOf(v);
        ch.value = r.numbers(v, 1)[0] * scale;
        double u = 0;
        if (parseFiniteNumber(attribute(v, "combinedUncertainty"), u)) ch.u = u * scale;
        d.characteristics.push_back(ch);
      }
  }
  d.runs = run;
  return d;
}

CmmDocument readQifResults(const std::string& path) { return parseQifResults(readFile(path), path); }

}  // namespace probeloop::interop
