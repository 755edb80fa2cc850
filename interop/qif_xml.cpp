#include "interop/qif_xml.hpp"

#include <algorithm>

namespace probeloop::interop::qifxml {

std::string local(const xmlNode* n) { return reinterpret_cast<const char*>(n->name); }

std::vector<xmlNodePtr> children(const xmlNode* n, const char* name) {
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
bool foreignElement(const xmlNode* n) {
  const std::string ns = n->ns && n->ns->href ? reinterpret_cast<const char*>(n->ns->href) : "";
  return !ns.empty() && ns != kNamespace;
}

CmmFeatureKind kindOf(const std::string& qif) {
  if (qif == "Plane") return CmmFeatureKind::Plane;
  if (qif == "Sphere") return CmmFeatureKind::Sphere;
  if (qif == "Cylinder") return CmmFeatureKind::Cylinder;
  if (qif == "Circle") return CmmFeatureKind::Circle;
  if (qif == "Point" || qif == "EdgePoint") return CmmFeatureKind::Point;
  if (qif == "Line") return CmmFeatureKind::Line;
  return CmmFeatureKind::Other;
}

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
  if (const auto* alg = child(e, "SubstituteFeatureAlgorithm")) {
    if (const auto* en = child(alg, "SubstituteFeatureAlgorithmEnum")) g.algorithm = text(en);
    else if (const auto* other = child(alg, "OtherSubstituteFeatureAlgorithm")) g.algorithm = "OTHER: " + text(other);
  }
  return g;
}


OpenedQif openQif(const std::string& xml, const std::string& file_name, bool strict) {
  xmlDocPtr raw = xmlReadMemory(xml.data(), static_cast<int>(xml.size()), file_name.c_str(), nullptr,
                                XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING | XML_PARSE_HUGE | XML_PARSE_BIG_LINES);
  if (!raw) {
    const xmlError* e = xmlGetLastError();
    throw InputError(file_name, e ? e->line : 0,
                     std::string("not well-formed XML: ") + (e && e->message ? e->message : "unreadable"));
  }
  OpenedQif q{DocPtr(raw), Reader(file_name, strict), nullptr, {}};
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

}  // namespace probeloop::interop::qifxml
