#include "interop/dmis.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <stdexcept>

#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::interop {

namespace {

// ---------------------------------------------------------------------------------------------
// Writing

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) throw std::logic_error("DMIS: a value to write is not finite");
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  if (s.rfind("-0.", 0) == 0 && s.find_first_not_of("-0.") == std::string::npos) s = s.substr(1);  // no "-0.000000"
  return s;
}
std::string xyz(const Eigen::Vector3d& p) { return fixed(p.x(), 6) + "," + fixed(p.y(), 6) + "," + fixed(p.z(), 6); }
std::string ijk(const Eigen::Vector3d& d) { return fixed(d.x(), 6) + "," + fixed(d.y(), 6) + "," + fixed(d.z(), 6); }

std::string label(const std::string& id) {
  std::string u = id;
  std::transform(u.begin(), u.end(), u.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  const bool ok = !u.empty() && u.size() <= 16 && std::isalpha(static_cast<unsigned char>(u[0])) &&
                  std::all_of(u.begin(), u.end(), [](unsigned char c) { return std::isalnum(c) || c == '_'; });
  if (!ok) throw std::logic_error("DMIS label '" + id + "': 1-16 characters [A-Z][A-Z0-9_]*");
  return u;
}
std::string pointLabel(const std::string& id, std::size_t k) {
  char buf[16];
  std::snprintf(buf, sizeof buf, k < 100 ? "_P%02zu" : "_P%zu", k);
  return label(id + buf);
}

// A text inside '...': no quote, no '$' (a continuation or comment mark), at most 60 characters.
std::string quoted(const std::string& t) {
  std::string out;
  for (char c : t.substr(0, 60)) out += c == '\'' ? '"' : c == '$' ? 'S' : c;
  return out;
}

// One statement, continued after a comma with '$' so that no line passes 80 characters.
void statement(std::ostringstream& o, const std::string& s) {
  std::string rest = s;
  while (rest.size() > 80) {
    std::size_t cut = rest.rfind(',', 78);
    if (cut == std::string::npos || cut == 0) break;
    o << rest.substr(0, cut + 1) << "$\n";
    rest = rest.substr(cut + 1);
  }
  o << rest << "\n";
}

// A measured direction to 9 decimals (as the QIF writer's): at 6, a plane's normal is read to
// 1 urad, a tenth of a um over 100 mm, and a thermal test piece's E_B is quantised to it.
std::string ijkMeasured(const Eigen::Vector3d& d) { return fixed(d.x(), 9) + "," + fixed(d.y(), 9) + "," + fixed(d.z(), 9); }

std::string featureStatement(const std::string& prefix, const CmmFeature& f, const CmmGeometry& g) {
  const std::string l = prefix + "(" + label(f.name) + ")=FEAT/";
  const std::string dir = prefix == "FA" ? ijkMeasured(g.direction) : ijk(g.direction);
  switch (f.kind) {
    case CmmFeatureKind::Plane: return l + "PLANE,CART," + xyz(g.location_mm) + "," + dir;
    case CmmFeatureKind::Cylinder:
      return l + "CYLNDR," + (f.internal ? "INNER" : "OUTER") + ",CART," + xyz(g.location_mm) + "," + dir + "," +
             fixed(g.diameter_mm, 6);
    case CmmFeatureKind::Sphere:
      return l + "SPHERE," + (f.internal ? "INNER" : "OUTER") + ",CART," + xyz(g.location_mm) + "," + fixed(g.diameter_mm, 6);
    default: throw std::logic_error(std::string("DMIS writer: a ") + cmmFeatureKindName(f.kind) + " feature is not written");
  }
}
const char* measType(CmmFeatureKind k) {
  return k == CmmFeatureKind::Plane ? "PLANE" : k == CmmFeatureKind::Cylinder ? "CYLNDR" : "SPHERE";
}

}  // namespace

std::string dmisProgram(const CmmDocument& plan, const std::string& title) {
  std::ostringstream o;
  double top = -1e300;
  for (const auto& f : plan.features)
    for (const auto& p : f.points) top = std::max(top, (p.p_mm + 5.0 * p.normal).z());
  const double clear = top + 20.0;
  o << "DMISMN/'" << quoted(title) << "',05.2\n";
  o << "$$ probeloop CMM plan\n";
  o << "$$ part frame, mm: the alignment must exist on the CMM before this program\n";
  o << "$$ PTMEAS ijk: the nominal outward surface normal; the probe travels along -ijk\n";
  o << "$$ moves: vertical, or at the clearance height Z " << fixed(clear, 3) << "\n";
  o << "$$ (20 mm above the highest approach start, 5 mm out along each normal)\n";
  o << "$$ SNSLCT/SA(...): the calibrated tip is site-specific; select it first\n";
  o << "UNITS/MM,ANGDEC\n";
  o << "MODE/PROG,MAN\n";
  for (const auto& f : plan.features) {
    statement(o, featureStatement("F", f, f.nominal));
    o << "MEAS/" << measType(f.kind) << ",F(" << label(f.name) << ")," << f.points.size() << "\n";
    for (const auto& p : f.points) {
      if (!(p.normal.norm() > 0)) throw std::logic_error("DMIS writer: a point of " + f.name + " without its normal");
      const Eigen::Vector3d start = p.p_mm + 5.0 * p.normal;
      statement(o, "GOTO/" + xyz(Eigen::Vector3d(start.x(), start.y(), clear)));
      statement(o, "GOTO/" + xyz(start));
      statement(o, "PTMEAS/CART," + xyz(p.p_mm) + "," + ijk(p.normal));
      statement(o, "GOTO/" + xyz(Eigen::Vector3d(start.x(), start.y(), clear)));
    }
    o << "ENDMES\n";
  }
  for (const auto& f : plan.features) o << "OUTPUT/FA(" << label(f.name) << ")\n";
  o << "ENDFIL\n";
  return o.str();
}

std::string dmisOutput(const CmmDocument& results, const std::string& title) {
  std::ostringstream o;
  o << "FILNAM/'" << quoted(title) << "',05.2\n";
  o << "$$ probeloop simulated CMM output; part frame, mm\n";
  o << "$$ FA(<feature>_Pnn)=FEAT/POINT: the feature's measured surface points\n";
  o << "$$ (ijk: the planned outward normal)\n";
  o << "UNITS/MM,ANGDEC\n";
  for (const auto& f : results.features) {
    o << "$$ " << label(f.name) << ": " << f.points.size() << " points\n";
    for (std::size_t k = 0; k < f.points.size(); ++k)
      statement(o, "FA(" + pointLabel(f.name, k + 1) + ")=FEAT/POINT,CART," + xyz(f.points[k].p_mm) + "," + ijk(f.points[k].normal));
    if (f.nominal.given) statement(o, featureStatement("F", f, f.nominal));
    if (f.measured.given) statement(o, featureStatement("FA", f, f.measured));
  }
  o << "ENDFIL\n";
  return o.str();
}

// ---------------------------------------------------------------------------------------------
// Reading

namespace {

struct Statement {
  int line = 0;
  std::string text;  // upper case outside quotes, blanks outside quotes removed
};

// Logical statements: CR stripped, '$$' comments dropped (a whole-line comment is never joined),
// a trailing single '$' joins the next physical line.
std::vector<Statement> statements(const std::string& text) {
  std::vector<Statement> out;
  std::istringstream in(text);
  std::string line, pending;
  int n = 0, start = 0;
  auto flush = [&] {
    Statement s;
    s.line = start;
    bool quoted = false;
    for (char c : pending) {
      if (c == '\'') quoted = !quoted;
      if (!quoted && (c == ' ' || c == '\t')) continue;
      s.text += quoted ? c : static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
    if (!s.text.empty()) out.push_back(s);
    pending.clear();
  };
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (n == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line = line.substr(3);
    const auto lead = line.find_first_not_of(" \t");
    if (lead == std::string::npos) continue;
    if (line.compare(lead, 2, "$$") == 0) continue;  // a whole-line comment: never joined
    // A trailing comment, outside quotes.
    bool quoted = false;
    for (std::size_t i = lead; i + 1 < line.size(); ++i) {
      if (line[i] == '\'') quoted = !quoted;
      if (!quoted && line[i] == '$' && line[i + 1] == '$') {
        line.resize(i);
        break;
      }
    }
    while (!line.empty() && (line.back() == ' ' || line.back() == '\t')) line.pop_back();
    if (pending.empty()) start = n;
    const bool continued = !line.empty() && line.back() == '$';
    if (continued) line.pop_back();
    pending += line.substr(std::min(lead, line.size()));
    if (!continued) flush();
  }
  if (!pending.empty()) flush();
  return out;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == ',') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

class Parser {
 public:
  Parser(const std::string& file) : file_(file) {}
  [[noreturn]] void fail(int line, const std::string& what) const { throw InputError(file_, line, what); }
  double number(int line, const std::string& s, const std::string& what) const {
    double v = 0;
    if (!parseFiniteNumber(s, v)) fail(line, what + ": '" + s + "' is not a number");
    return v;
  }
  Eigen::Vector3d point(int line, const std::vector<std::string>& f, std::size_t at, const std::string& what) const {
    if (f.size() < at + 3) fail(line, what + ": expected x,y,z");
    return Eigen::Vector3d(number(line, f[at], what), number(line, f[at + 1], what), number(line, f[at + 2], what)) * mm_per_unit;
  }
  // Direction cosines (normalised), or direction angles in degrees as GEOPAK writes them: a
  // component beyond 1, all within 0..180, whose cosines form a unit vector (within 1e-3). Zero:
  // none (a point without its vector); refused where a direction is needed (required).
  Eigen::Vector3d vector(int line, const std::vector<std::string>& f, std::size_t at, const std::string& what, bool required) const {
    if (f.size() < at + 3) fail(line, what + ": expected i,j,k");
    Eigen::Vector3d v(number(line, f[at], what), number(line, f[at + 1], what), number(line, f[at + 2], what));
    if (v.cwiseAbs().maxCoeff() > 1.0001 && v.minCoeff() >= 0 && v.maxCoeff() <= 180) {
      const Eigen::Vector3d c(std::cos(v.x() * M_PI / 180), std::cos(v.y() * M_PI / 180), std::cos(v.z() * M_PI / 180));
      if (std::fabs(c.norm() - 1) < 1e-3) v = c;
    }
    if (v.norm() == 0) {
      if (required) fail(line, what + ": i,j,k is a zero vector");
      return v;
    }
    return v.normalized();
  }
  double mm_per_unit = 1.0;
  std::string file_;
};

// "F(ID)=FEAT/..." -> prefix F, label ID, the rest after '='.
bool labelled(const std::string& s, std::string& prefix, std::string& lab, std::string& rest) {
  const auto open = s.find('('), close = s.find(')'), eq = s.find('=');
  if (open == std::string::npos || close == std::string::npos || eq == std::string::npos || !(open < close && close < eq)) return false;
  prefix = s.substr(0, open);
  lab = s.substr(open + 1, close - open - 1);
  rest = s.substr(eq + 1);
  return !prefix.empty() && !lab.empty();
}

// A feature statement must carry its label: "F(X)=FEAT/..." or "FA(X)=FEAT/...".
void requireLabel(const Parser& p, const Statement& s) {
  std::string prefix, lab, rest;
  if (s.text.find("=FEAT/") != std::string::npos && !labelled(s.text, prefix, lab, rest))
    p.fail(s.line, "a FEAT statement without its label: expected F(label)=FEAT/... or FA(label)=FEAT/...");
}

// FEAT/<type>,... into a feature (kind, INNER/OUTER, geometry); false for a type we do not read.
bool feature(const Parser& p, int line, const std::string& body, CmmFeature& f, CmmGeometry& g, Eigen::Vector3d* point_normal) {
  auto a = split(body.substr(5));  // after "FEAT/"
  const std::string type = a[0];
  std::size_t i = 1;
  if (i < a.size() && (a[i] == "INNER" || a[i] == "OUTER")) f.internal = a[i++] == "INNER";
  if (i >= a.size() || a[i] != "CART") {
    if (type == "POINT" || type == "PLANE" || type == "CYLNDR" || type == "SPHERE" || type == "CIRCLE")
      p.fail(line, "FEAT/" + type + ": expected CART coordinates (POL is not read)");
    return false;
  }
  ++i;
  g.given = true;
  g.location_mm = p.point(line, a, i, "FEAT/" + type);
  i += 3;
  auto more = [&](std::size_t k) { return a.size() >= i + k; };
  if (type == "POINT") {
    f.kind = CmmFeatureKind::Point;
    if (more(3)) *point_normal = p.vector(line, a, i, "FEAT/POINT", false);
  } else if (type == "PLANE") {
    f.kind = CmmFeatureKind::Plane;
    g.direction = p.vector(line, a, i, "FEAT/PLANE", true);
  } else if (type == "CYLNDR" || type == "CIRCLE") {
    f.kind = type == "CYLNDR" ? CmmFeatureKind::Cylinder : CmmFeatureKind::Circle;
    g.direction = p.vector(line, a, i, "FEAT/" + type, true);
    if (!more(4)) p.fail(line, "FEAT/" + type + ": expected the diameter after i,j,k");
    g.diameter_mm = p.number(line, a[i + 3], "FEAT/" + type + " diameter") * p.mm_per_unit;
  } else if (type == "SPHERE") {
    f.kind = CmmFeatureKind::Sphere;
    if (!more(1)) p.fail(line, "FEAT/SPHERE: expected the diameter after x,y,z");
    g.diameter_mm = p.number(line, a[i], "FEAT/SPHERE diameter") * p.mm_per_unit;
  } else {
    return false;
  }
  return true;
}

std::string keyword(const std::string& s) {
  std::string lab, prefix, rest;
  if (labelled(s, prefix, lab, rest)) return prefix + "()=" + rest.substr(0, rest.find('/'));
  return s.substr(0, s.find('/'));
}

void units(Parser& p, const Statement& s) {
  const auto a = split(s.text.substr(6));
  if (a[0] == "MM") p.mm_per_unit = 1.0;
  else if (a[0] == "INCH") p.mm_per_unit = 25.4;
  else if (a[0] == "CM") p.mm_per_unit = 10.0;
  else if (a[0] == "METER" || a[0] == "M") p.mm_per_unit = 1000.0;
  else p.fail(s.line, "UNITS/" + a[0] + ": expected MM, CM, METER or INCH");
}

std::string unitName(double mm_per_unit) {
  return mm_per_unit == 1.0 ? "mm" : mm_per_unit == 25.4 ? "inch" : mm_per_unit == 10.0 ? "cm" : "m";
}

void noteSkipped(CmmDocument& d, const std::map<std::string, int>& skipped) {
  for (const auto& [k, n] : skipped) d.notes.push_back(std::to_string(n) + " x " + k + " passed over");
}

}  // namespace

bool looksLikeDmis(const std::string& text) {
  for (const auto& s : statements(text.substr(0, 4096)))
    return s.text.rfind("DMISMN", 0) == 0 || s.text.rfind("FILNAM", 0) == 0 || s.text.rfind("DMISMD", 0) == 0;
  return false;
}

bool isDmisProgram(const std::string& text) {
  for (const auto& s : statements(text.substr(0, 4096))) return s.text.rfind("DMISMN", 0) == 0 || s.text.rfind("DMISMD", 0) == 0;
  return false;
}

CmmDocument parseDmisProgram(const std::string& text, const std::string& file_name, const CmmReadOptions& options) {
  Parser p(file_name);
  CmmDocument d;
  d.file = file_name;
  std::map<std::string, std::size_t> index;
  std::map<std::string, int> skipped;
  constexpr std::size_t none = static_cast<std::size_t>(-1);
  std::size_t meas = none;  // an index: the vector may grow
  std::size_t expected = 0;
  int meas_line = 0;
  auto lenient = [&](int line, const std::string& problem, const std::string& done) {
    if (options.strict) p.fail(line, problem);
    d.warnings.push_back({line, problem + "; " + done});
  };
  // A block whose ENDMES is missing but whose PTMEAS count is its n: closed where the next
  // block, ENDFIL or the end of the file shows it ended (a count that does not add up is refused).
  auto closeUnended = [&](int line, const std::string& where) {
    const auto& f = d.features[meas];
    if (f.points.size() != expected)
      p.fail(meas_line, "MEAS: no ENDMES, and " + std::to_string(f.points.size()) + " PTMEAS where MEAS/..,F(" + f.name + ")," +
                            std::to_string(expected) + " announced");
    lenient(line, "the MEAS block of line " + std::to_string(meas_line) + " has no ENDMES",
            "closed " + where + " (its " + std::to_string(expected) + " PTMEAS as announced)");
    meas = none;
  };
  const auto all_statements = statements(text);
  bool ended = false;
  for (const auto& s : all_statements) {
    std::string prefix, lab, rest;
    if (ended) {
      lenient(s.line, "statements after ENDFIL", "passed over");
      break;
    }
    requireLabel(p, s);
    if (s.text.rfind("UNITS/", 0) == 0) {
      units(p, s);
    } else if (labelled(s.text, prefix, lab, rest) && prefix == "F" && rest.rfind("FEAT/", 0) == 0) {
      if (meas != none) p.fail(s.line, "FEAT inside the MEAS block of line " + std::to_string(meas_line) + " (its ENDMES first)");
      CmmFeature f;
      f.name = lab;
      f.line = s.line;
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      if (!feature(p, s.line, rest, f, f.nominal, &n)) {
        ++skipped["FEAT/" + rest.substr(5, rest.find(',') - 5)];
        continue;
      }
      const auto again = index.find(lab);
      if (again != index.end()) {
        // A label defined again: DMIS's later definition replaces the earlier one.
        lenient(s.line, "F(" + lab + ") defined again (first at line " + std::to_string(d.features[again->second].line) + ")",
                "the later definition read");
        f.points = std::move(d.features[again->second].points);  // measured before: kept
        d.features[again->second] = f;
        continue;
      }
      index[lab] = d.features.size();
      d.features.push_back(f);
    } else if (s.text.rfind("MEAS/", 0) == 0) {
      if (meas != none) closeUnended(s.line, "before the MEAS of this line");
      const auto a = split(s.text.substr(5));
      if (a.size() < 3 || a[1].rfind("F(", 0) != 0 || a[1].back() != ')') p.fail(s.line, "MEAS: expected MEAS/<type>,F(label),n");
      const std::string l = a[1].substr(2, a[1].size() - 3);
      if (!index.count(l)) p.fail(s.line, "MEAS: F(" + l + ") is not defined by a FEAT before it");
      meas = index[l];
      const double n = p.number(s.line, a[2], "MEAS point count");
      if (n < 1 || n > 1e8 || n != std::floor(n)) p.fail(s.line, "MEAS point count: a whole number from 1 to 100000000");
      expected = static_cast<std::size_t>(n);
      meas_line = s.line;
      d.features[meas].points.clear();
    } else if (s.text.rfind("PTMEAS/", 0) == 0) {
      if (meas == none) p.fail(s.line, "PTMEAS outside a MEAS block");
      const auto a = split(s.text.substr(7));
      if (a[0] != "CART") p.fail(s.line, "PTMEAS: expected CART coordinates");
      CmmPoint q;
      q.p_mm = p.point(s.line, a, 1, "PTMEAS");
      if (a.size() >= 7) q.normal = p.vector(s.line, a, 4, "PTMEAS", false);
      d.features[meas].points.push_back(q);
      d.moves.push_back({s.line, q.p_mm, true});
    } else if (s.text.rfind("GOTO/", 0) == 0) {
      auto a = split(s.text.substr(5));
      const std::size_t at = a[0] == "CART" ? 1 : 0;
      d.moves.push_back({s.line, p.point(s.line, a, at, "GOTO"), false});
    } else if (s.text == "ENDMES") {
      if (meas == none) {
        lenient(s.line, "ENDMES without MEAS", "passed over");
        continue;
      }
      const auto& f = d.features[meas];
      if (f.points.size() != expected)
        p.fail(meas_line, "MEAS/..,F(" + f.name + ")," + std::to_string(expected) + ": " + std::to_string(f.points.size()) +
                              " PTMEAS in the block");
      meas = none;
    } else if (s.text.rfind("ENDFIL", 0) == 0) {
      if (meas != none) closeUnended(s.line, "at ENDFIL");
      ended = true;
    } else if (s.text.rfind("DMISMN", 0) == 0 || s.text.rfind("DMISMD", 0) == 0) {
      continue;  // the header
    } else {
      ++skipped[keyword(s.text)];
    }
  }
  if (meas != none) closeUnended(all_statements.back().line, "at the end of the file");
  if (!ended && !all_statements.empty())
    lenient(all_statements.back().line, "no ENDFIL after the last statement (the file may be cut short)", "what is there was read");
  d.length_unit = unitName(p.mm_per_unit);
  noteSkipped(d, skipped);
  return d;
}

CmmDocument parseDmisOutput(const std::string& text, const std::string& file_name, const CmmReadOptions& options) {
  Parser p(file_name);
  CmmDocument d;
  d.file = file_name;
  d.runs = 1;
  struct Actual {
    CmmFeature f;
    CmmGeometry g;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    bool actual = false;
  };
  std::vector<Actual> all;
  std::map<std::string, std::pair<std::size_t, int>> seen;  // "F(X)" / "FA(X)" -> its place in all, its first line
  std::map<std::string, int> skipped;
  const auto all_statements = statements(text);
  bool ended = false;
  // A form mistake that keeps what was read: a warning, or refused when strict.
  auto lenient = [&](int line, const std::string& problem, const std::string& done) {
    if (options.strict) p.fail(line, problem);
    d.warnings.push_back({line, problem + "; " + done});
  };
  for (const auto& s : all_statements) {
    std::string prefix, lab, rest;
    if (ended) {
      lenient(s.line, "statements after ENDFIL", "passed over");
      break;
    }
    requireLabel(p, s);
    if (s.text.rfind("UNITS/", 0) == 0) {
      units(p, s);
      continue;
    }
    if (labelled(s.text, prefix, lab, rest) && (prefix == "FA" || prefix == "F") && rest.rfind("FEAT/", 0) == 0) {
      Actual a;
      a.f.name = lab;
      a.f.line = s.line;
      a.f.run = 1;
      a.actual = prefix == "FA";
      if (!feature(p, s.line, rest, a.f, a.g, &a.normal)) {
        ++skipped["FEAT/" + rest.substr(5, rest.find(',') - 5)];
        continue;
      }
      const std::string key = prefix + "(" + lab + ")";
      if (const auto again = seen.find(key); again != seen.end()) {
        // Reported again (a feature measured twice, a point re-taken): the later report is the
        // result. Its kind must agree: another kind is another meaning.
        auto& earlier = all[again->second.first];
        if (earlier.f.kind != a.f.kind)
          p.fail(s.line, key + "=FEAT/: a " + cmmFeatureKindName(a.f.kind) + ", but line " + std::to_string(earlier.f.line) + " makes " +
                             lab + " a " + cmmFeatureKindName(earlier.f.kind));
        lenient(s.line, key + " reported again (first at line " + std::to_string(again->second.second) + ")", "the later one read");
        earlier = a;
        continue;
      }
      seen[key] = {all.size(), s.line};
      all.push_back(a);
      continue;
    }
    if (s.text.rfind("ENDFIL", 0) == 0) {
      ended = true;
      continue;
    }
    if (s.text.rfind("FILNAM", 0) == 0 || s.text.rfind("DMISMN", 0) == 0) continue;  // the header
    ++skipped[keyword(s.text)];
  }
  if (!ended && !all_statements.empty())
    lenient(all_statements.back().line, "no ENDFIL after the last statement (the file may be cut short)",
            "what is there was read");
  // Features: every actual that is not a point of another feature; nominals fill in.
  std::map<std::string, std::size_t> index;
  auto ownerOf = [&](const std::string& l) -> std::string {
    const auto at = l.rfind("_P");
    if (at == std::string::npos || at + 2 >= l.size() ||
        !std::all_of(l.begin() + static_cast<long>(at) + 2, l.end(), [](unsigned char c) { return std::isdigit(c); }))
      return "";
    const std::string owner = l.substr(0, at);
    for (const auto& a : all)
      if (a.f.name == owner && a.f.kind != CmmFeatureKind::Point) return owner;
    return "";
  };
  for (const auto& a : all) {
    if (a.f.kind == CmmFeatureKind::Point && !ownerOf(a.f.name).empty()) continue;
    auto it = index.find(a.f.name);
    if (it == index.end()) {
      it = index.emplace(a.f.name, d.features.size()).first;
      CmmFeature f = a.f;
      f.nominal = f.measured = CmmGeometry{};
      d.features.push_back(f);
    }
    auto& f = d.features[it->second];
    if (f.kind != a.f.kind)
      p.fail(a.f.line, (a.actual ? "FA(" : "F(") + a.f.name + ")=FEAT/: a " + cmmFeatureKindName(a.f.kind) + ", but line " +
                           std::to_string(f.line) + " makes " + a.f.name + " a " + cmmFeatureKindName(f.kind));
    (a.actual ? f.measured : f.nominal) = a.g;
    if (a.actual) f.line = a.f.line;
    if (f.kind == CmmFeatureKind::Point && a.actual) f.points.push_back({a.g.location_mm, a.normal});
  }
  for (const auto& a : all) {
    if (a.f.kind != CmmFeatureKind::Point || !a.actual) continue;
    const std::string owner = ownerOf(a.f.name);
    if (owner.empty()) continue;
    auto& f = d.features[index.at(owner)];
    f.points.push_back({a.g.location_mm, a.normal});
    if (f.line == 0 || a.f.line < f.line) f.line = a.f.line;  // the feature's first line: its first point
  }
  // Features known only by a nominal were planned, not reported: not measurements.
  d.features.erase(std::remove_if(d.features.begin(), d.features.end(), [](const CmmFeature& f) { return !f.measured.given && f.points.empty(); }),
                   d.features.end());
  d.length_unit = unitName(p.mm_per_unit);
  noteSkipped(d, skipped);
  return d;
}

}  // namespace probeloop::interop
