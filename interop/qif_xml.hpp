// Reading QIF with libxml2, shared by the plan and results readers (qif_read.cpp) and the
// writer's document type: element access by local name, the unit-aware Reader, and openQif
// (well-formedness, no DTD, root, namespace, version, units). Internal to interop.
//
// Leniency (docs/interop.md#lenient-reading): Reader::lenient is where a producer's mistake
// that keeps the meaning is either a warning (file line + what was done, into the document's
// warnings) or, with strict, the same message as an InputError.
#pragma once
#include <libxml/parser.h>
#include <libxml/tree.h>

#include <cmath>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "interop/cmm_document.hpp"

namespace probeloop::interop::qifxml {

constexpr const char* kNamespace = "http://qifstandards.org/xsd/qif3";

struct DocDeleter {
  void operator()(xmlDoc* d) const { xmlFreeDoc(d); }
};
using DocPtr = std::unique_ptr<xmlDoc, DocDeleter>;

std::string local(const xmlNode* n);
std::vector<xmlNodePtr> children(const xmlNode* n, const char* name = nullptr);
xmlNodePtr child(const xmlNode* n, const char* name);
std::string text(const xmlNode* n);
std::string attribute(const xmlNode* n, const char* name);
int lineOf(const xmlNode* n);
// True for an element in a namespace other than QIF's (a producer's extension).
bool foreignElement(const xmlNode* n);

class Reader {
 public:
  Reader(const std::string& file, bool strict = false) : file_(file), strict_(strict) {}

  // A producer's mistake that keeps the meaning: a warning at n's line ("problem; what was
  // done"), or, when strict, an InputError at that line with the problem alone.
  void lenient(const xmlNode* n, const std::string& problem, const std::string& done, CmmDocument& d) const {
    if (strict_) fail(n, problem);
    d.warnings.push_back({n ? lineOf(n) : 0, problem + "; " + done});
  }

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
  bool strict_ = false;
  double scale_ = 1.0, angle_scale_ = 1.0;
  std::map<std::string, const xmlNode*> named_, angular_named_;
};

CmmFeatureKind kindOf(const std::string& qif);
// The geometry a feature nominal or measurement carries, by kind (all of it optional).
CmmGeometry geometryOf(const Reader& r, const xmlNode* e, CmmFeatureKind kind);

inline const std::string kMeasurementSuffix = "FeatureMeasurement";
constexpr double kMaxPoints = 1e8;  // per point set: a bound, so that 3 x count cannot overflow

struct OpenedQif {
  DocPtr doc;
  Reader r;
  const xmlNode* root = nullptr;
  CmmDocument d;
};

// Parses, checks the root, namespace and version, reads the units.
OpenedQif openQif(const std::string& xml, const std::string& file_name, bool strict);

// The [from, to) range of a point set of n points that a PointList reference selects.
std::pair<std::size_t, std::size_t> selected(const Reader& r, const xmlNode* ref, std::size_t n);

}  // namespace probeloop::interop::qifxml
