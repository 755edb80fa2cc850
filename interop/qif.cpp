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
#include "interop/qif_xml.hpp"

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

using qifxml::DocPtr;
using qifxml::kNamespace;

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
    if (!g.algorithm.empty() && g.algorithm.rfind("OTHER: ", 0) != 0)
      w.add(w.add(e, "SubstituteFeatureAlgorithm"), "SubstituteFeatureAlgorithmEnum", g.algorithm);
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
// Reading: qif_read.cpp (documents), qif_xml.cpp (the XML and units).

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

}  // namespace probeloop::interop
